// The C++ client library against the real skinstreamd replaying the demo subject over loopback:
// each encoding's vertices against the daemon's own float vertex buffer of the same frame, and
// the bad paths (no daemon, a refused Hello, bytes that break the protocol) as one-line errors.
#include "skinstream/client.h"

#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include "protocol/subscriber/subscriber_stream.h"
#include "support/client_frames.h"
#include "support/daemon_process.h"
#include "support/received_vertices.h"
#include "support/scripted_daemon.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using client::Encoding;
using test::compare;
using test::Difference;
using test::Received;

// Frames by number from one subscriber, until it has `count` frames past the first.
std::map<uint32_t, Received> receive(uint16_t port, Encoding encoding, bool normals, int count, size_t* model_bytes = nullptr) {
  client::Options options;
  options.port = port;
  options.encoding = encoding;
  options.normals = normals;
  client::Subscriber sub(options);
  auto frames = test::receive_frames<Received>(sub, count, test::keep_vertices);
  EXPECT_EQ(sub.mesh().encoding, encoding);
  if (model_bytes) *model_bytes = sub.model_bytes();
  return frames;
}

// The demo subject (53,514 vertices) replaying its jump-rope take; four subscribers of the
// library at once, one per encoding, compared frame by frame with the float subscriber.
TEST(ClientSubscriberDemo, EveryEncodingGivesTheDaemonsVertices) {
  const std::string demo = SKINSTREAM_DEMO_DIR;
  // A fifth of real time: every subscriber takes every frame on this shared machine.
  test::DaemonProcess daemon("--subject " + demo + "/subject.sksubj --replay " + demo + "/live.c3d --loop --speed 0.2");
  ASSERT_GT(daemon.sub_port, 0);
  const uint16_t port = static_cast<uint16_t>(daemon.sub_port);
  constexpr int kFrames = 40;
  std::map<uint32_t, Received> by_encoding[4];
  size_t model_bytes = 0;
  std::vector<std::thread> threads;
  for (int e = 0; e < 4; ++e)
    threads.emplace_back([&, e] { by_encoding[e] = receive(port, static_cast<Encoding>(e), true, kFrames, e == 3 ? &model_bytes : nullptr); });
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
  const auto& reference = by_encoding[static_cast<int>(Encoding::Float)];
  ASSERT_EQ(static_cast<int>(reference.size()), kFrames);
  ASSERT_EQ(reference.begin()->second.positions.size(), 3u * 53514u);

  // Parameters, evaluated here with the daemon's own evaluator on the same floats: within the
  // 0.01 mm the library promises (the same code and numbers give the same bits).
  const Difference parameters = compare(reference, by_encoding[static_cast<int>(Encoding::Parameters)]);
  EXPECT_GE(parameters.frames, kFrames / 2);
  EXPECT_LE(parameters.position_mm, 0.01);
  EXPECT_LE(parameters.normal_degrees, 0.01);
  EXPECT_GT(model_bytes, 0u);
  EXPECT_LE(model_bytes, 4u << 20);  // the bound for the demo subject

  // Quantised: half of a step of the frame's box (under 2.5 m / 65535 / 2); normals within half
  // a 1/32767 step per component.
  const Difference quantised = compare(reference, by_encoding[static_cast<int>(Encoding::Quantised)]);
  EXPECT_GE(quantised.frames, kFrames / 2);
  EXPECT_LE(quantised.position_mm, 0.02);
  EXPECT_LE(quantised.normal_degrees, 0.01);

  // Compressed: half of a step of the key's grid (the body plus 250 mm a side, under 3 m /
  // 65535 / 2); 8-bit octahedral normals within 1.5 degrees (the worst of the demo's: 1.25).
  const Difference compressed = compare(reference, by_encoding[static_cast<int>(Encoding::Compressed)]);
  EXPECT_GE(compressed.frames, kFrames / 2);
  EXPECT_LE(compressed.position_mm, 0.025);
  EXPECT_LE(compressed.normal_degrees, 1.5);
  std::printf("largest differences from the float buffer over %d/%d/%d frames: parameters %.3g mm %.3g deg, quantised %.3g mm, "
              "compressed %.3g mm %.4g deg; Model message %zu bytes\n",
              parameters.frames, quantised.frames, compressed.frames, parameters.position_mm, parameters.normal_degrees,
              quantised.position_mm, compressed.position_mm, compressed.normal_degrees, model_bytes);
}

// A subscriber that asks for MeshInfo and the Model packed (the default) and one that asks
// for them plain: the same mesh, the same Model bytes and the same vertices, for a third of the
// bytes before the first frame.
TEST(ClientSubscriberDemo, PackedAndPlainJoinersGetTheSameMeshModelAndVertices) {
  const std::string demo = SKINSTREAM_DEMO_DIR;
  test::DaemonProcess daemon("--subject " + demo + "/subject.sksubj --replay " + demo +
                             "/live.c3d --loop --speed 0.2");
  ASSERT_GT(daemon.sub_port, 0);
  struct Joiner {
    std::map<uint32_t, Received> frames;
    client::Mesh mesh;
    std::vector<unsigned char> model;
    uint64_t bytes_before_first_frame = 0;
  };
  Joiner joiners[2];  // packed, plain
  // After the replay's first frames: the rate in MeshInfo is known (packed at start-up without
  // it, the packed MeshInfo then carries it too).
  std::this_thread::sleep_for(std::chrono::seconds(1));
  std::vector<std::thread> threads;
  for (int plain = 0; plain < 2; ++plain)
    threads.emplace_back([&, plain] {
      client::Options options;
      options.port = static_cast<uint16_t>(daemon.sub_port);
      options.encoding = Encoding::Parameters;
      options.packed = plain == 0;
      client::Subscriber sub(options);
      Joiner& j = joiners[plain];
      j.frames = test::receive_frames<Received>(sub, 20, [&](const client::Frame& frame, Received& kept) {
        if (j.bytes_before_first_frame == 0) j.bytes_before_first_frame = sub.bytes_received();
        test::keep_vertices(frame, kept);
      });
      j.mesh = sub.mesh();
      j.model.assign(sub.model_payload().begin(), sub.model_payload().end());
    });
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
  const Joiner &packed = joiners[0], &plain = joiners[1];
  EXPECT_EQ(packed.mesh.indices, plain.mesh.indices);
  EXPECT_EQ(packed.mesh.dominant_part, plain.mesh.dominant_part);
  EXPECT_EQ(packed.mesh.marker_names, plain.mesh.marker_names);
  EXPECT_EQ(packed.mesh.source_rate_hz, 120.0f);
  EXPECT_EQ(plain.mesh.source_rate_hz, 120.0f);
  ASSERT_FALSE(plain.model.empty());
  EXPECT_EQ(packed.model, plain.model) << "the Model's floats bit for bit";
  const Difference difference = compare(plain.frames, packed.frames);
  EXPECT_GE(difference.frames, 10);
  EXPECT_EQ(difference.position_mm, 0.0);
  EXPECT_LT(packed.bytes_before_first_frame * 2.5, plain.bytes_before_first_frame)
      << packed.bytes_before_first_frame << " bytes packed, " << plain.bytes_before_first_frame << " plain";
  std::printf("bytes before the first frame: packed %llu, plain %llu\n",
              static_cast<unsigned long long>(packed.bytes_before_first_frame),
              static_cast<unsigned long long>(plain.bytes_before_first_frame));
}

TEST(ClientSubscriberDemo, AnUnknownSubjectIsRefusedWithTheReason) {
  const std::string demo = SKINSTREAM_DEMO_DIR;
  test::DaemonProcess daemon("--subject " + demo + "/subject.sksubj");
  client::Options options;
  options.port = static_cast<uint16_t>(daemon.sub_port);
  options.subject = "Actor9";
  client::Subscriber sub(options);
  client::Frame frame;
  try {
    sub.next(frame, std::chrono::seconds(10));
    FAIL() << "no refusal";
  } catch (const client::Error& e) {
    EXPECT_NE(std::string(e.what()).find("refused"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Actor9"), std::string::npos) << e.what();
  }
}

TEST(ClientSubscriber, NoDaemonIsAOneLineError) {
  // A port nothing listens on: bound, then closed.
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof address;
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  close(fd);
  client::Options options;
  options.port = ntohs(address.sin_port);
  try {
    client::Subscriber sub(options);
    FAIL() << "connected to nothing";
  } catch (const client::Error& e) {
    EXPECT_NE(std::string(e.what()).find("refused"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
  EXPECT_THROW(client::Subscriber(client::Options{.encoding = Encoding::Parameters, .protocol_version = 1}), std::invalid_argument);
}

std::string error_for(std::vector<unsigned char> reply, Encoding encoding = Encoding::Parameters) {
  // Then closes: a stream that ends inside a message is an error too.
  test::ScriptedDaemon daemon(std::move(reply), test::ScriptedDaemon::Then::Close);
  client::Options options;
  options.port = daemon.port;
  options.encoding = encoding;
  client::Subscriber sub(options);
  client::Frame frame;
  try {
    while (sub.next(frame, std::chrono::seconds(5))) {
    }
    return "no error";
  } catch (const client::Error& e) {
    return e.what();
  }
}

// A Frame message's flags (after the 12-byte header and the frame number) and vertex count
// (after the three times), little-endian.
constexpr size_t wire_flags_offset = 12 + 4;
constexpr size_t wire_vertex_count_offset = 12 + 32;

std::vector<unsigned char> golden(const std::string& name) {
  const std::string bytes = test::read_bytes(test::source_path("tests/protocol/fixtures/subscriber/" + name));
  return {bytes.begin(), bytes.end()};
}

TEST(ClientSubscriber, BytesThatBreakTheProtocolAreOneLineErrors) {
  std::vector<unsigned char> bad_magic = golden("mesh_info_v2.bin");
  bad_magic[0] = 'X';
  EXPECT_NE(error_for(bad_magic).find("bad magic"), std::string::npos);
  std::vector<unsigned char> version_one = golden("mesh_info.bin");  // a version 1 answer to a version 2 Hello
  EXPECT_NE(error_for(version_one).find("version 1"), std::string::npos);
  // A Model before MeshInfo; a Model whose vertex count differs from MeshInfo's.
  EXPECT_NE(error_for(golden("model.bin")).find("before MeshInfo"), std::string::npos);
  std::vector<unsigned char> both = golden("mesh_info_v2.bin");
  const std::vector<unsigned char> model = golden("model.bin");  // 3 vertices; the MeshInfo has 4
  both.insert(both.end(), model.begin(), model.end());
  EXPECT_NE(error_for(both).find("vertices"), std::string::npos);
  // A truncated Model message: the connection ends inside it.
  std::vector<unsigned char> cut = golden("mesh_info_v2.bin");
  cut.insert(cut.end(), model.begin(), model.end() - 10);
  EXPECT_NE(error_for(cut).find("closed the connection"), std::string::npos);
  // A parameter Frame before any Model.
  std::vector<unsigned char> frame_first = golden("mesh_info_v2.bin");
  const std::vector<unsigned char> parameters = golden("frame_v2_parameters.bin");
  frame_first.insert(frame_first.end(), parameters.begin(), parameters.end());
  EXPECT_NE(error_for(frame_first).find("before the Model"), std::string::npos);
  for (const std::string& e : {error_for(bad_magic), error_for(version_one), error_for(frame_first)})
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

TEST(ClientSubscriber, PackedMessagesGetThePlainOnesChecksAndTheirOwn) {
  // Unpacked, a Model of 3 vertices after a MeshInfo of 4 is refused as it is plain.
  std::vector<unsigned char> both = golden("packed_mesh_info_v2.bin");
  const std::vector<unsigned char> model = golden("packed_model.bin");
  both.insert(both.end(), model.begin(), model.end());
  EXPECT_NE(error_for(both).find("vertices"), std::string::npos) << error_for(both);
  // A deflated stream that does not inflate.
  std::vector<unsigned char> corrupt = golden("packed_mesh_info_v2.bin");
  corrupt[12 + 8 + 20 + 3] ^= 0xFF;
  const std::string corrupt_error = error_for(corrupt);
  EXPECT_NE(corrupt_error.find("bad message from the daemon: Packed"), std::string::npos) << corrupt_error;
  EXPECT_EQ(corrupt_error.find('\n'), std::string::npos) << corrupt_error;
  // Packed to a subscriber that asked for plain messages.
  test::ScriptedDaemon daemon(golden("packed_mesh_info_v2.bin"), test::ScriptedDaemon::Then::Close);
  client::Subscriber sub({.port = daemon.port, .encoding = Encoding::Parameters, .packed = false});
  client::Frame frame;
  try {
    while (sub.next(frame, std::chrono::seconds(5))) {
    }
    FAIL() << "took a Packed message it did not ask for";
  } catch (const client::Error& e) {
    EXPECT_NE(std::string(e.what()).find("did not ask for"), std::string::npos) << e.what();
  }
}

// One Frame whose parameters are not finite (an RBF weight) among good ones: skipped, counted and
// said why; the frames after it arrive as before. (The library ended the stream with an Error.)
TEST(ClientSubscriber, AFrameThatIsNotFiniteIsSkippedAndTheStreamGoesOn) {
  test::ScriptedDaemon daemon(test::broken_frame_stream(10, 4));
  client::Options options;
  options.port = daemon.port;
  options.encoding = Encoding::Parameters;
  client::Subscriber sub(options);
  std::vector<uint32_t> numbers;
  client::Frame frame;
  while (numbers.size() < 9 && sub.next(frame, std::chrono::seconds(5))) {
    numbers.push_back(frame.frame_number);
    ASSERT_EQ(frame.positions.size(), 9u);
    for (float v : frame.positions) ASSERT_TRUE(std::isfinite(v)) << "frame " << frame.frame_number;
  }
  EXPECT_EQ(numbers, (std::vector<uint32_t>{1, 2, 3, 5, 6, 7, 8, 9, 10}));
  EXPECT_EQ(sub.frames_rejected(), 1u);
  EXPECT_EQ(sub.last_rejection(), "frame skipped: parameters: an RBF weight is not finite");
}

// A version 2 MeshInfo of `vertices` vertices (no faces, float) and `markers` empty marker names.
std::vector<unsigned char> mesh_info_of(uint32_t vertices, uint32_t markers) {
  std::vector<unsigned char> payload;
  auto put = [&](const auto& value) {
    const auto* b = reinterpret_cast<const unsigned char*>(&value);
    payload.insert(payload.end(), b, b + sizeof value);
  };
  put(vertices);
  put(uint32_t{0});  // faces
  put(markers);
  put(uint32_t{1});  // parts
  put(120.0f);
  payload.resize(payload.size() + vertices, 0);  // each vertex's part
  put(uint32_t{0});                               // marker triangles
  payload.resize(payload.size() + 2 * size_t{markers}, 0);  // empty names
  put(uint16_t{0});  // subject
  put(uint32_t{0});  // float
  put(uint32_t{0});  // no compressed order
  std::vector<unsigned char> message(subscriber::kHeaderBytes);
  subscriber::write_header(subscriber::MessageType::MeshInfo, subscriber::kVersion2, payload.size(),
                           std::span<unsigned char, subscriber::kHeaderBytes>(message.data(), subscriber::kHeaderBytes));
  message.insert(message.end(), payload.begin(), payload.end());
  return message;
}

long peak_resident_kb() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  return 0;
}

// A MeshInfo announcing 67 million vertices (a 64 MiB message) or 8 million empty marker names:
// the subscriber sized its buffers from them (3.35 GB, 651 MB). Now each count is checked
// against the subscriber's limits before anything is made for it.
TEST(ClientSubscriber, AMeshInfoBeyondTheLimitsIsAnErrorBeforeAnythingIsMade) {
  const long before = peak_resident_kb();
  const std::string vertices = error_for(mesh_info_of(67'000'000, 0), Encoding::Float);
  const std::string markers = error_for(mesh_info_of(3, 8'000'000), Encoding::Float);
  EXPECT_NE(vertices.find("MeshInfo: 67000000 vertices, more than this subscriber takes (4000000, its max_vertices)"), std::string::npos)
      << vertices;
  EXPECT_NE(markers.find("MeshInfo: 8000000 markers, more than this subscriber takes (4096, its max_markers)"), std::string::npos) << markers;
  std::printf("peak resident memory grew by %ld kB (the 64 MiB message, kept by the daemon written here and read once)\n",
              peak_resident_kb() - before);
}

// A daemon that sends MeshInfo and then half a message and nothing more, its connection open:
// next() returned false for ever. After silence_timeout it is an Error that says so.
TEST(ClientSubscriber, ADaemonThatFallsSilentIsAnErrorAfterTheSilenceTimeout) {
  std::vector<unsigned char> reply = golden("mesh_info_v2.bin");
  const std::vector<unsigned char> status = golden("status_v2.bin");
  reply.insert(reply.end(), status.begin(), status.begin() + 20);  // its header and 8 bytes of it
  test::ScriptedDaemon daemon(reply);
  client::Options options;
  options.port = daemon.port;
  options.encoding = Encoding::Compressed;
  options.silence_timeout = std::chrono::milliseconds(500);
  client::Subscriber sub(options);
  client::Frame frame;
  std::string error = "no error within 10 s";
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  try {
    while (std::chrono::steady_clock::now() < give_up) sub.next(frame, std::chrono::milliseconds(200));
  } catch (const client::Error& e) {
    error = e.what();
  }
  EXPECT_EQ(error, "nothing from the daemon for 500 ms, and it says something every second: gone, or a message cut short (20 bytes of one came)");
}

// The daemon's words in an error are made printable: a refusal whose detail holds a line break
// and a terminal escape cannot add a line of its own to the subscriber's output.
TEST(ClientSubscriber, TheDaemonsWordsInAnErrorArePrintable) {
  subscriber::Status status;
  status.state = subscriber::SourceStateCode::Refused;
  status.detail = "no\n\x1b[31mskinstream-sub: error: forged";
  const std::string error = error_for(subscriber::encode_status(status, subscriber::kVersion2));
  EXPECT_EQ(error, "the daemon refused this subscriber: no\\x0a\\x1b[31mskinstream-sub: error: forged");
}

// A paced subscriber acknowledges the compressed deltas it has to skip (their key gave way in its
// queue) as well as the frames it shows: the daemon sends nothing while two wait for an Ack.
TEST(ClientSubscriber, PacedSubscriberAcknowledgesSkippedFrames) {
  std::vector<unsigned char> reply = golden("mesh_info_v2.bin");  // 4 vertices, compressed
  std::vector<unsigned char> delta = golden("frame_v2_compressed.bin");
  delta[wire_flags_offset] &= ~0x40;  // not a key frame: a delta of key 1234, which it never saw
  delta[wire_vertex_count_offset] = 4;  // the MeshInfo's 4 vertices (the coded bytes are never read)
  for (int i = 0; i < 3; ++i) reply.insert(reply.end(), delta.begin(), delta.end());
  const int listener = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof address;
  ASSERT_EQ(bind(listener, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  listen(listener, 1);
  getsockname(listener, reinterpret_cast<sockaddr*>(&address), &length);
  size_t acknowledged_bytes = 0;
  std::thread daemon([&] {
    const int peer = accept(listener, nullptr, nullptr);
    unsigned char buffer[1024];
    recv(peer, buffer, sizeof buffer, 0);  // the Hello
    send(peer, reply.data(), reply.size(), MSG_NOSIGNAL);
    for (ssize_t n; (n = recv(peer, buffer, sizeof buffer, 0)) > 0;) acknowledged_bytes += static_cast<size_t>(n);
    close(peer);
  });
  {
    client::Options options;
    options.port = ntohs(address.sin_port);
    options.encoding = Encoding::Compressed;
    options.paced = true;
    client::Subscriber sub(options);
    client::Frame frame;
    EXPECT_FALSE(sub.next(frame, std::chrono::milliseconds(1500)));
    EXPECT_EQ(sub.frames_skipped(), 3u);
  }  // closes the connection: the daemon thread reads to the end
  daemon.join();
  close(listener);
  EXPECT_EQ(acknowledged_bytes, 3u * 16u);  // three Acks of 12 + 4 bytes
}

}  // namespace
}  // namespace skinstream
