#pragma once
// A take's per-frame table (tab-separated text, a header line then a line a frame): what a C3D
// file has no place for (the source's frame numbers, times and timecode; each published
// sample's status). Lines are queued, then written and synced with the take's C3D files, so
// after a crash the table ends at a whole line at most a commit behind; recover_frame_table()
// drops a partial last line.

#include <cstdint>
#include <string>

namespace skinstream::server {

class FrameTable {
 public:
  // Creates `path` (refuses one that exists) and queues the header line. Throws FileError.
  FrameTable(std::string path, const std::string& header);
  ~FrameTable();
  FrameTable(const FrameTable&) = delete;
  FrameTable& operator=(const FrameTable&) = delete;

  std::string& line() { return pending_; }  // append a line's text and '\n' here
  void commit();                            // writes what was queued and syncs it; throws FileError
  void close();                             // commit and close

 private:
  std::string path_;
  int fd_ = -1;
  std::string pending_;
};

// Cuts a table a killed writer left after its last whole line; returns the frame lines kept.
// Throws FileError.
uint64_t recover_frame_table(const std::string& path);

}  // namespace skinstream::server
