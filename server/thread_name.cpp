#include "server/thread_name.h"

#include <pthread.h>

namespace skinstream::server {

namespace {
constexpr size_t kMaxNameLength = 15;  // the kernel's TASK_COMM_LEN, less the terminating zero
}

bool name_this_thread(std::string_view name) {
  const std::string cut(name.substr(0, kMaxNameLength));
  return pthread_setname_np(pthread_self(), cut.c_str()) == 0;
}

std::string this_thread_name() {
  char name[kMaxNameLength + 1] = {};
  if (pthread_getname_np(pthread_self(), name, sizeof(name)) != 0) return {};
  return name;
}

}  // namespace skinstream::server
