// NatNet datagrams as skinstream's NatNet client and replay server meet them: each input is one
// datagram, decoded by decode_message in every layout read (3.0, 3.1, 4.0, 4.1 and a later 4.x).
// Whatever the bytes, a refusal is one printable line; a frame's counts agree with what it holds;
// and decoding into a Message reused from the layout before (as a client reuses its frame, for
// an allocation-free stream) gives the same frame as decoding into a fresh one.
#include <cstdlib>
#include <cstring>
#include <string>

#include "fuzz/one_line_file_error.h"
#include "protocol/natnet/natnet_reader.h"

namespace natnet = skinstream::natnet;

namespace {

bool same_points(const std::vector<natnet::Point>& a, const std::vector<natnet::Point>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(natnet::Point)) == 0);
}

bool same_frame(const natnet::FrameOfData& a, const natnet::FrameOfData& b) {
  if (a.frame_number != b.frame_number || a.marker_set_count != b.marker_set_count || !same_points(a.other_markers, b.other_markers) ||
      a.labelled_markers.size() != b.labelled_markers.size() || a.rigid_bodies != b.rigid_bodies || a.skeletons != b.skeletons ||
      a.assets != b.assets || a.force_plates != b.force_plates || a.devices != b.devices || a.timecode != b.timecode ||
      a.timecode_subframe != b.timecode_subframe || std::memcmp(&a.timestamp_s, &b.timestamp_s, sizeof(double)) != 0 ||
      a.stamp_mid_exposure != b.stamp_mid_exposure || a.stamp_data_received != b.stamp_data_received ||
      a.stamp_transmit != b.stamp_transmit || a.precise_seconds != b.precise_seconds || a.precise_fraction != b.precise_fraction ||
      a.params != b.params)
    return false;
  for (size_t s = 0; s < a.marker_set_count; ++s)
    if (a.marker_sets[s].name != b.marker_sets[s].name || !same_points(a.marker_sets[s].positions, b.marker_sets[s].positions)) return false;
  for (size_t m = 0; m < a.labelled_markers.size(); ++m) {
    const natnet::LabelledMarker &x = a.labelled_markers[m], &y = b.labelled_markers[m];
    if (x.id != y.id || std::memcmp(x.position.data(), y.position.data(), sizeof(natnet::Point)) != 0 ||
        std::memcmp(&x.size, &y.size, sizeof(float)) != 0 || x.params != y.params || std::memcmp(&x.residual, &y.residual, sizeof(float)) != 0)
      return false;
  }
  return true;
}

bool same_definitions(const natnet::ModelDefinitions& a, const natnet::ModelDefinitions& b) {
  if (a.skipped_descriptions != b.skipped_descriptions || a.marker_sets.size() != b.marker_sets.size()) return false;
  for (size_t s = 0; s < a.marker_sets.size(); ++s)
    if (a.marker_sets[s].name != b.marker_sets[s].name || a.marker_sets[s].markers != b.marker_sets[s].markers) return false;
  return true;
}

constexpr natnet::Version kLayouts[] = {{3, 0}, {3, 1}, {4, 0}, {4, 1}, {4, 2}};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const natnet::Bytes datagram(data, size);
  natnet::Message reused;
  for (const natnet::Version version : kLayouts) {
    natnet::Message fresh;
    std::string error, reused_error;
    const bool ok = natnet::decode_message(datagram, version, fresh, error);
    if (!ok) skinstream::fuzz::expect_one_printable_line(error);
    const bool reused_ok = natnet::decode_message(datagram, version, reused, reused_error);
    if (ok != reused_ok || error != reused_error) std::abort();
    if (!ok) continue;
    if (fresh.id == natnet::message::FrameOfData) {
      const natnet::FrameOfData& f = fresh.frame;
      if (f.marker_set_count > f.marker_sets.size()) std::abort();
      if (!same_frame(f, reused.frame)) std::abort();
    }
    if (fresh.id == natnet::message::ModelDef && !same_definitions(fresh.model_definitions, reused.model_definitions)) std::abort();
  }
  return 0;
}
