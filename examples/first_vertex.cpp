// Subscribes to a skinstreamd and prints vertex 0 of each frame; reconnects with backoff when
// the daemon goes away. Usage: first_vertex HOST PORT [float|quantised|compressed|parameters] [FRAMES]
#include <skinstream/client.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s HOST PORT [float|quantised|compressed|parameters] [FRAMES]\n", argv[0]);
    return 2;
  }
  skinstream::client::Options options;
  options.host = argv[1];
  options.port = static_cast<uint16_t>(std::atoi(argv[2]));
  try {
    options.encoding = skinstream::client::encoding_from_string(argc > 3 ? argv[3] : "parameters");
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  options.normals = false;
  const long wanted = argc > 4 ? std::atol(argv[4]) : 0;  // 0: until interrupted
  long printed = 0;
  auto backoff = std::chrono::milliseconds(250);
  while (wanted == 0 || printed < wanted) {
    try {
      skinstream::client::Subscriber subscriber(options);
      skinstream::client::Frame frame;
      while (wanted == 0 || printed < wanted) {
        if (!subscriber.next(frame, std::chrono::seconds(1)) || frame.positions.empty()) continue;
        std::printf("frame %u vertex 0: %.4f %.4f %.4f mm (%s)\n", frame.frame_number, frame.positions[0], frame.positions[1],
                    frame.positions[2], skinstream::client::to_string(subscriber.mesh().encoding));
        std::fflush(stdout);
        ++printed;
        backoff = std::chrono::milliseconds(250);
      }
    } catch (const skinstream::client::Error& e) {
      std::fprintf(stderr, "%s; retrying in %lld ms\n", e.what(), static_cast<long long>(backoff.count()));
      std::this_thread::sleep_for(backoff);
      backoff = std::min(backoff * 2, std::chrono::milliseconds(4000));
    }
  }
  return 0;
}
