#pragma once
// One file descriptor held back (on /dev/null) for the moment the process runs out: a listener
// that meets "Too many open files" with a connection it must serve (the HTTP port, so /health
// answers while subscribers hold every other descriptor) closes the reserve and accepts into the
// slot it frees. Every listener takes the reserve back, when a slot is free again, before its
// next accept, so the subscriber port cannot keep it. One thread (the io thread) uses it.

namespace skinstream::server {

class DescriptorReserve {
 public:
  DescriptorReserve();  // holds one descriptor if the process has one to spare
  ~DescriptorReserve();
  DescriptorReserve(const DescriptorReserve&) = delete;
  DescriptorReserve& operator=(const DescriptorReserve&) = delete;

  // Closes the reserve; false when none was held.
  bool release();
  // Takes one descriptor again if none is held and one is free.
  void restore();

 private:
  int fd_ = -1;
};

}  // namespace skinstream::server
