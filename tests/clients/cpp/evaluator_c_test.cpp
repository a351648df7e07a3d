// The C ABI of the client library's evaluator (include/skinstream/evaluator_c.h), as a C or
// ctypes caller uses it: the golden Model of the protocol's fixtures in its reference pose, the
// bad inputs as one-line errors that leave the outputs alone, and the demo subject's parameter
// blocks from the real skinstreamd evaluated into the daemon's float buffer bit for bit.
#include "skinstream/evaluator_c.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "skinstream/client.h"
#include "support/client_frames.h"
#include "support/daemon_process.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

constexpr size_t kHeaderBytes = 12;  // of every subscriber message: the payload follows

std::vector<unsigned char> fixture_payload(const std::string& name) {
  std::ifstream in(test::source_path("tests/protocol/fixtures/subscriber/" + name), std::ios::binary);
  EXPECT_TRUE(in) << name;
  std::vector<unsigned char> message{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  return {message.begin() + static_cast<std::ptrdiff_t>(std::min(kHeaderBytes, message.size())),
          message.end()};
}

void append(std::vector<unsigned char>& out, const void* bytes, size_t n) {
  const auto* b = static_cast<const unsigned char*>(bytes);
  out.insert(out.end(), b, b + n);
}

// A parameter block holding every part at its reference frame (A = [I 0 0], R0, d0), which
// gives back the reference vertices. model.bin (make_v2_fixtures.py): 3 vertices, 2 parts of
// 2 and 1 members; its parts' R0 and d0 follow the 16 count bytes and 36 vertex bytes.
std::vector<unsigned char> reference_pose_block(const std::vector<unsigned char>& model, uint32_t flags = 0) {
  const uint32_t parts = 2, members = 3;
  std::vector<unsigned char> block;
  append(block, &parts, 4);
  append(block, &members, 4);
  for (uint32_t p = 0; p < parts; ++p) {
    float a[27] = {};
    for (int r = 0; r < 3; ++r) a[9 * r + r] = 1.0f;
    append(block, a, sizeof a);
    append(block, model.data() + 16 + 36 + 80 * p, 48);  // R0 (9 floats) and d0 (3)
    append(block, &flags, 4);
  }
  const std::vector<float> weights(3 * members, 0.0f);
  append(block, weights.data(), 4 * weights.size());
  return block;
}

struct Evaluator {
  skinstream_evaluator* handle;
  ~Evaluator() { skinstream_evaluator_destroy(handle); }
};

TEST(EvaluatorC, TheVersionIsTheHeaders) {
  EXPECT_EQ(skinstream_evaluator_abi_version(), SKINSTREAM_EVALUATOR_ABI_VERSION);
}

TEST(EvaluatorC, BadModelsAndFacesAreOneLineErrors) {
  const std::vector<unsigned char> model = fixture_payload("model.bin");
  const uint32_t triangle[3] = {0, 1, 2}, out_of_range[3] = {0, 1, 3};
  struct Case {
    const char* what;
    const unsigned char* payload;
    size_t bytes;
    const uint32_t* faces;
    size_t face_count;
  };
  const Case cases[] = {
      {"Model: ", model.data(), model.size() - 4, triangle, 1},  // truncated
      {"Model: no payload", nullptr, 16, triangle, 1},
      {"faces: none given for a count of 1", model.data(), model.size(), nullptr, 1},
      {"is more than a mesh holds", model.data(), model.size(), triangle, size_t{1} << 40},
      {"Model: evaluation model: face 0 refers to vertex 3 of 3", model.data(), model.size(), out_of_range,
       1},
  };
  for (const Case& c : cases) {
    char error[256] = "untouched";
    EXPECT_EQ(skinstream_evaluator_create(c.payload, c.bytes, c.faces, c.face_count, error, sizeof error),
              nullptr)
        << c.what;
    const std::string line = error;
    EXPECT_NE(line.find(c.what), std::string::npos) << line;
    EXPECT_EQ(line.find('\n'), std::string::npos) << line;
  }
  // No room for the error, or a room of one byte: nothing is written past it.
  EXPECT_EQ(skinstream_evaluator_create(model.data(), 3, nullptr, 0, nullptr, 0), nullptr);
  char one[2] = {'x', 'y'};
  EXPECT_EQ(skinstream_evaluator_create(model.data(), 3, nullptr, 0, one, 1), nullptr);
  EXPECT_EQ(one[0], '\0');
  EXPECT_EQ(one[1], 'y');
  skinstream_evaluator_destroy(nullptr);
}

TEST(EvaluatorC, TheReferencePoseGivesTheReferenceVertices) {
  const std::vector<unsigned char> model = fixture_payload("model.bin");
  const uint32_t triangle[3] = {0, 1, 2};
  char error[256] = "";
  Evaluator e{skinstream_evaluator_create(model.data(), model.size(), triangle, 1, error, sizeof error)};
  ASSERT_NE(e.handle, nullptr) << error;
  ASSERT_EQ(skinstream_evaluator_vertex_count(e.handle), 3u);
  float reference[9];
  std::memcpy(reference, model.data() + 16, sizeof reference);
  for (uint32_t rbf : {0u, 1u}) {  // the RBF term with zero weights adds nothing
    const std::vector<unsigned char> block = reference_pose_block(model, rbf);
    float positions[9], normals[9];
    ASSERT_EQ(skinstream_evaluator_evaluate(e.handle, block.data(), block.size(), positions, normals, error,
                                            sizeof error),
              0)
        << error;
    for (int i = 0; i < 9; ++i) EXPECT_NEAR(positions[i], reference[i], 1e-3) << i;
    float length = 0.0f;
    for (int i = 0; i < 3; ++i) length += normals[i] * normals[i];
    EXPECT_NEAR(length, 1.0f, 1e-5);  // a vertex of the triangle
    // Without normals asked for.
    ASSERT_EQ(skinstream_evaluator_evaluate(e.handle, block.data(), block.size(), positions, nullptr, error,
                                            sizeof error),
              0);
  }
}

TEST(EvaluatorC, BadBlocksAreOneLineErrorsAndLeaveTheOutputs) {
  const std::vector<unsigned char> model = fixture_payload("model.bin");
  Evaluator e{skinstream_evaluator_create(model.data(), model.size(), nullptr, 0, nullptr, 0)};
  ASSERT_NE(e.handle, nullptr);
  const std::vector<unsigned char> good = reference_pose_block(model);
  std::vector<unsigned char> nan = good;
  const float not_a_number = std::nanf("");
  std::memcpy(nan.data() + 8 + 4, &not_a_number, 4);  // part 0's A[0][1]
  const std::vector<unsigned char> truncated(good.begin(), good.end() - 4);
  std::vector<unsigned char> fewer_members = good;
  const uint32_t two = 2;
  std::memcpy(fewer_members.data() + 4, &two, 4);
  fewer_members.resize(fewer_members.size() - 12);
  struct Case {
    const char* what;
    const std::vector<unsigned char>* block;
  };
  for (const Case& c : {Case{"parameters: part 0 has a value that is not finite", &nan},
                        Case{"parameters: block of 360 bytes, the counts say 364", &truncated},
                        Case{"parameters: 2 parts and 2 members, the model has 2 and 3", &fewer_members}}) {
    float positions[9], normals[9];
    std::fill(positions, positions + 9, 7.0f);
    std::fill(normals, normals + 9, 7.0f);
    char error[256] = "";
    const std::vector<unsigned char>& block = *c.block;
    EXPECT_NE(skinstream_evaluator_evaluate(e.handle, block.data(), block.size(), positions, normals, error,
                                            sizeof error),
              0)
        << c.what;
    EXPECT_EQ(std::string(error), c.what);
    EXPECT_EQ(std::string(error).find('\n'), std::string::npos) << error;
    for (int i = 0; i < 9; ++i) EXPECT_EQ(positions[i], 7.0f);
    for (int i = 0; i < 9; ++i) EXPECT_EQ(normals[i], 7.0f);
  }
  char error[256] = "";
  float positions[9];
  EXPECT_NE(skinstream_evaluator_evaluate(nullptr, good.data(), good.size(), positions, nullptr, error,
                                          sizeof error),
            0);
  EXPECT_STREQ(error, "parameters: no evaluator");
  EXPECT_NE(skinstream_evaluator_evaluate(e.handle, good.data(), good.size(), nullptr, nullptr, error,
                                          sizeof error),
            0);
  EXPECT_STREQ(error, "parameters: no output for the positions");
  EXPECT_NE(skinstream_evaluator_evaluate(e.handle, nullptr, 8, positions, nullptr, error, sizeof error), 0);
  EXPECT_STREQ(error, "parameters: no block");
}

struct ReceivedFrame {
  std::vector<float> positions, normals;
  std::vector<unsigned char> block;
};

// Frames by number from one subscriber of the client library: the float encoding's vertices and
// normals, or the parameter encoding's blocks (not evaluated) with the Model and the faces.
std::map<uint32_t, ReceivedFrame> receive(uint16_t port, client::Encoding encoding, int count,
                                     std::vector<unsigned char>* model, std::vector<uint32_t>* faces) {
  client::Options options;
  options.port = port;
  options.encoding = encoding;
  options.evaluate = false;
  client::Subscriber sub(options);
  auto frames = test::receive_frames<ReceivedFrame>(sub, count, [&sub](const client::Frame& frame, ReceivedFrame& r) {
    r.positions.assign(frame.positions.begin(), frame.positions.end());
    r.normals.assign(frame.normals.begin(), frame.normals.end());
    r.block.assign(sub.parameter_block().begin(), sub.parameter_block().end());
  });
  if (model) model->assign(sub.model_payload().begin(), sub.model_payload().end());
  if (faces) *faces = sub.mesh().indices;
  return frames;
}

// The demo subject (53,514 vertices) replaying its take: each parameter block the daemon sent,
// evaluated through the C ABI, is the float buffer it sent for that frame, positions and
// normals bit for bit (the daemon's own evaluator on the same floats).
TEST(EvaluatorCDemo, EqualsTheDaemonsFloatBufferBitForBit) {
  const std::string demo = SKINSTREAM_DEMO_DIR;
  test::DaemonProcess daemon("--subject " + demo + "/subject.sksubj --replay " + demo + "/live.c3d --loop --speed 0.2");
  ASSERT_GT(daemon.sub_port, 0);
  const uint16_t port = static_cast<uint16_t>(daemon.sub_port);
  constexpr int kFrames = 20;
  std::map<uint32_t, ReceivedFrame> floats, parameters;
  std::vector<unsigned char> model;
  std::vector<uint32_t> faces;
  std::thread float_thread(
      [&] { floats = receive(port, client::Encoding::Float, kFrames, nullptr, nullptr); });
  parameters = receive(port, client::Encoding::Parameters, kFrames, &model, &faces);
  float_thread.join();
  EXPECT_EQ(daemon.stop(), 0) << daemon.log();
  ASSERT_FALSE(model.empty());
  char error[256] = "";
  Evaluator e{skinstream_evaluator_create(model.data(), model.size(), faces.data(), faces.size() / 3, error,
                                          sizeof error)};
  ASSERT_NE(e.handle, nullptr) << error;
  const uint32_t vertex_count = skinstream_evaluator_vertex_count(e.handle);
  ASSERT_EQ(vertex_count, 53514u);
  std::vector<float> positions(3 * vertex_count), normals(3 * vertex_count);
  int compared = 0;
  for (const auto& [number, frame] : parameters) {
    const auto it = floats.find(number);
    if (it == floats.end()) continue;
    ++compared;
    ASSERT_EQ(skinstream_evaluator_evaluate(e.handle, frame.block.data(), frame.block.size(),
                                            positions.data(), normals.data(), error, sizeof error),
              0)
        << error;
    ASSERT_EQ(it->second.positions.size(), positions.size());
    ASSERT_EQ(it->second.normals.size(), normals.size());
    EXPECT_EQ(std::memcmp(positions.data(), it->second.positions.data(), 4 * positions.size()), 0)
        << "frame " << number;
    EXPECT_EQ(std::memcmp(normals.data(), it->second.normals.data(), 4 * normals.size()), 0)
        << "frame " << number;
  }
  EXPECT_GE(compared, kFrames / 2);
  std::printf("%d frames evaluated through the C ABI, equal to the float buffer bit for bit\n", compared);
}

}  // namespace
}  // namespace skinstream
