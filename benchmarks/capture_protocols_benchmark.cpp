// Cost of reading one frame of each capture system's wire format, as the daemon's sources do on
// their network thread: a dense take of 350 labelled markers and 25 unlabelled points (the
// generator's flex take, replay_data/synthetic/flex_2s_seed1.c3d), each frame encoded once by the
// replay encoders, then decoded in turn (Vicon DataStream: split + LabeledRecons +
// UnlabeledRecons; QTM RT: the Data packet; NatNet 3.1 and 4.1: the frame of data).
//   build/bin/capture_protocols_benchmark --benchmark_format=json
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "protocol/files/capture_file.h"
#include "protocol/natnet/natnet_capture_encoder.h"
#include "protocol/natnet/natnet_reader.h"
#include "protocol/qtm/qtm_capture_encoder.h"
#include "protocol/qtm/qtm_packet_reader.h"
#include "protocol/vicon/vicon_capture_encoder.h"
#include "protocol/vicon/vicon_packet_reader.h"

namespace skinstream {
namespace {

const Capture& take() {
  static const Capture capture =
      read_capture(std::string(SKINSTREAM_SOURCE_DIR) + "/replay_data/synthetic/flex_2s_seed1.c3d");
  return capture;
}

template <typename Decode>
void decode_frames(benchmark::State& state, const std::vector<std::vector<unsigned char>>& frames, Decode decode) {
  size_t next = 0, bytes = 0;
  for (auto _ : state) {
    const auto& frame = frames[next];
    if (!decode(frame)) state.SkipWithError("a frame did not decode");
    bytes += frame.size();
    next = (next + 1) % frames.size();
  }
  state.SetBytesProcessed(static_cast<int64_t>(bytes));
  state.counters["frame_bytes"] = static_cast<double>(frames[0].size());
}

void BM_DecodeViconFrame(benchmark::State& state) {
  vicon::CaptureFrameEncoder encoder(take(), "flex");
  vicon::PacketWriter writer;
  std::vector<std::vector<unsigned char>> frames;
  for (int k = 0; k < take().frame_count; ++k) {
    encoder.encode_frame(k, static_cast<uint32_t>(k + 1), false, writer);
    const auto bytes = writer.finish();
    frames.emplace_back(bytes.begin(), bytes.end());
  }
  std::vector<vicon::ObjectView> objects;
  std::vector<vicon::LabeledRecon> labeled;
  std::vector<vicon::UnlabeledRecon> unlabeled;
  std::string error;
  decode_frames(state, frames, [&](const std::vector<unsigned char>& frame) {
    if (!vicon::split_objects(frame, objects, error)) return false;
    for (const vicon::ObjectView& o : objects) {
      if (o.type == vicon::object_type::LabeledRecons && !vicon::decode(o.payload, labeled, error)) return false;
      if (o.type == vicon::object_type::UnlabeledRecons && !vicon::decode(o.payload, unlabeled, error)) return false;
    }
    benchmark::DoNotOptimize(labeled.data());
    return true;
  });
}

void BM_DecodeQtmFrame(benchmark::State& state) {
  qtm::CaptureEncoder encoder({{"flex", &take()}});
  qtm::DataPacketWriter writer;
  std::vector<std::vector<unsigned char>> frames;
  for (int k = 0; k < take().frame_count; ++k) {
    const auto bytes = encoder.encode_frame(static_cast<uint64_t>(k), writer);
    frames.emplace_back(bytes.begin(), bytes.end());
  }
  qtm::DataFrame data;
  std::string error;
  decode_frames(state, frames, [&](const std::vector<unsigned char>& frame) {
    const bool ok = qtm::decode_data(frame, data, error);
    benchmark::DoNotOptimize(data.labelled.data());
    return ok;
  });
}

void decode_natnet(benchmark::State& state, natnet::Version version) {
  natnet::CaptureEncoder encoder({{"flex", &take()}});
  std::vector<std::vector<unsigned char>> frames(static_cast<size_t>(take().frame_count));
  for (int k = 0; k < take().frame_count; ++k) encoder.encode(static_cast<uint64_t>(k), version, frames[static_cast<size_t>(k)]);
  natnet::FrameOfData data;
  std::string error;
  decode_frames(state, frames, [&](const std::vector<unsigned char>& frame) {
    uint16_t id = 0;
    natnet::Bytes payload;
    const bool ok = natnet::read_message(frame, id, payload, error) && natnet::decode_frame(payload, version, data, error);
    benchmark::DoNotOptimize(data.labelled_markers.data());
    return ok;
  });
}
void BM_DecodeNatNet31Frame(benchmark::State& state) { decode_natnet(state, {3, 1}); }
void BM_DecodeNatNet41Frame(benchmark::State& state) { decode_natnet(state, {4, 1}); }

BENCHMARK(BM_DecodeViconFrame);
BENCHMARK(BM_DecodeQtmFrame);
BENCHMARK(BM_DecodeNatNet31Frame);
BENCHMARK(BM_DecodeNatNet41Frame);

}  // namespace
}  // namespace skinstream

BENCHMARK_MAIN();
