// The pipeline thread with a real subscriber on loopback: a real take (CMU 85_12, with gaps cut
// into it) is filled, a mesh deformed over two threads, the frame encoded and handed to a TCP
// subscriber. In steady state the pipeline thread allocates nothing per frame, from taking the
// frame to handing it to every subscriber.
#include "server/pipeline/pipeline.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

#include "core/offline/subject_builder.h"
#include "protocol/files/capture_file.h"
#include "server/publish/subscriber_hub.h"
#include "server/publish/tcp_subscriber.h"
#include "support/allocation_counter.h"
#include "support/subscriber_client.h"
#include "support/test_data.h"

namespace skinstream::server {
namespace {

// One part made of every marker, over a mesh of the markers' own reference positions and a
// copy of them 20 mm out (faces between consecutive markers): small, but every stage of the
// deformation runs.
DeformationModel one_part_over(const SubjectModel& subject) {
  DeformationModel model;
  model.part_names = {"all"};
  for (int m = 0; m < subject.marker_count(); ++m) model.part_members.push_back({m, 1.0});
  model.part_member_offsets.push_back(subject.marker_count());
  for (const Vec3& p : subject.reference_positions) model.reference_vertices.push_back(p);
  for (const Vec3& p : subject.reference_positions) model.reference_vertices.push_back(p + Vec3(0, 0, 20));
  const int n = subject.marker_count();
  for (int v = 0; v < 2 * n; ++v) {
    model.vertex_influences.push_back({0, 1.0});
    model.vertex_influence_offsets.push_back(static_cast<int>(model.vertex_influences.size()));
  }
  for (int m = 0; m + 1 < n; ++m) {
    model.faces.push_back({m, m + 1, n + m});
    model.faces.push_back({m + 1, n + m + 1, n + m});
  }
  return model;
}

// Passes frames on to the hub and counts the pipeline thread's heap allocations from the
// publish of frame `first` to that of frame `last`: everything the thread did for the frames
// in between.
class CountingConsumer : public FrameConsumer {
 public:
  CountingConsumer(SubscriberHub& hub, int first, int last) : hub_(hub), first_(first), last_(last) {}
  StreamKeySet wanted_encodings() const override { return hub_.wanted_encodings(); }
  void publish(const FrameRef& frame) override {
    hub_.publish(frame);
    const int n = ++published_;
    if (n == first_) counter_.emplace();
    if (n == last_) {
      allocations_ = counter_->count();
      counter_.reset();
      measured_.store(true);
    }
  }
  bool measured() const { return measured_.load(); }
  size_t allocations() const { return allocations_; }

 private:
  SubscriberHub& hub_;
  const int first_, last_;
  int published_ = 0;
  std::optional<test::CountAllocations> counter_;
  size_t allocations_ = 0;
  std::atomic<bool> measured_{false};
};

TEST(Pipeline, AllocatesNothingPerFrameFromMailboxToSubscriber) {
  const SubjectModel subject = build_subject(read_capture(test::source_path("replay_data/cmu/85_02.c3d")), {});
  const Capture take = read_capture(test::source_path("replay_data/cmu/85_12.c3d"));
  ASSERT_EQ(take.point_count(), subject.marker_count());
  const DeformationModel deformation = one_part_over(subject);
  ASSERT_EQ(deformation.validate(subject.marker_count()), "");

  asio::io_context io;
  auto guard = asio::make_work_guard(io);
  std::thread io_thread([&] { io.run(); });
  Metrics metrics;
  subscriber::MeshInfo info;
  info.vertex_count = static_cast<uint32_t>(deformation.vertex_count());
  info.marker_count = static_cast<uint32_t>(subject.marker_count());
  info.part_count = 1;
  info.marker_names = subject.marker_names;
  for (const auto& f : deformation.faces)
    info.faces.push_back({static_cast<uint32_t>(f[0]), static_cast<uint32_t>(f[1]), static_cast<uint32_t>(f[2])});
  info.dominant_part.assign(info.vertex_count, 0);
  SubscriberHub hub(metrics, HubOptions{}, info, true);

  tcp::acceptor acceptor(io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
  acceptor.async_accept([&](const boost::system::error_code& ec, tcp::socket socket) {
    ASSERT_FALSE(ec) << ec.message();
    auto session = std::make_shared<TcpSubscriber>(io, hub, std::move(socket), "test");
    hub.add(session);
    session->start();
  });
  // The subscriber wants everything a renderer can ask for (positions, normals, markers).
  std::atomic<int> frames_received{0};
  std::thread subscriber_thread([&, port = acceptor.local_endpoint().port()] {
    try {
      sub::SubscriberClient client("127.0.0.1", std::to_string(port), subscriber::kWantNormals | subscriber::kWantMarkers);
      client.run([&](subscriber::MessageType type, std::span<const unsigned char>, int64_t) {
        if (type == subscriber::MessageType::Frame) ++frames_received;
        return true;
      });
    } catch (const std::exception& e) {
      ADD_FAILURE() << "subscriber: " << e.what();
    }
  });
  constexpr int kFrames = 200, kFirst = 40, kLast = 180;
  FrameMailbox mailbox(subject.marker_count());  // what the pipeline uses lives longer than it
  CountingConsumer consumer(hub, kFirst, kLast);
  // However the test ends, in the daemon's order: the pipeline stopped, the subscribers closed on
  // the io thread and the threads joined (every handler that held a frame has run), and only then
  // the pipeline and its frame pool destroyed (declared before the teardown, so destroyed after
  // it: a subscriber still writing a pooled frame when the pool went was a use after free).
  std::optional<Pipeline> pipeline;
  struct Teardown {
    std::function<void()> run;
    ~Teardown() { run(); }
  } teardown{[&] {
    if (pipeline) pipeline->stop();
    asio::post(io, [&] {
      hub.close_all();
      acceptor.close();  // a still pending accept (the subscriber never came) ends too
    });
    guard.reset();
    io_thread.join();
    subscriber_thread.join();
  }};
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (hub.wanted_encodings().empty() && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  ASSERT_FALSE(hub.wanted_encodings().empty()) << "the subscriber never said Hello";

  PipelineOptions options;
  options.deform_threads = 2;
  pipeline.emplace(subject, &deformation, options, mailbox, consumer, metrics);
  // As the daemon's hub does when a subscriber says Hello (here it said it before the pipeline
  // existed): the pool's buffers for what it wants are made off the pipeline thread, and so are
  // those of every frame the pool adds later, whenever the machine's load makes it add one.
  hub.wanted_encodings().for_each([&](StreamKey key) { pipeline->prepare_encoding(key); });
  pipeline->start();
  for (int f = 0; f < kFrames; ++f) {
    MarkerFrame& frame = mailbox.writable();
    frame.clear();
    frame.frame_number = static_cast<uint32_t>(f);
    frame.source_rate_hz = take.rate_hz;
    frame.source_time_ns = static_cast<int64_t>(f * 1e9 / take.rate_hz);
    frame.receive_time_ns = sub::wall_clock_ns();
    // Gaps of 15 frames rolling over the markers (the take itself is cleaned): they are filled.
    for (int m = 0; m < subject.marker_count(); ++m)
      frame.labelled[m] = f >= 20 && (m + f / 15) % 13 == 0 ? missing_point() : take.at(f, m);
    mailbox.post(1);
    // Lockstep with the subscriber: every frame is processed and received (when fed as fast as
    // the pipeline runs, a subscriber on a busy machine falls behind its queue of 2).
    while (frames_received.load() < f + 1 && std::chrono::steady_clock::now() < give_up) std::this_thread::yield();
  }
  ASSERT_TRUE(consumer.measured()) << "published " << pipeline->frames_published();
  EXPECT_EQ(consumer.allocations(), 0u) << "heap allocations on the pipeline thread over " << kLast - kFirst << " frames";
  EXPECT_EQ(mailbox.dropped(), 0u);

  EXPECT_EQ(frames_received.load(), kFrames);
  EXPECT_GT(metrics.markers_filled.load(), 0u);  // the gaps went through the filler
}

// Nobody's consumer: wants nothing.
class NoConsumer : public FrameConsumer {
 public:
  StreamKeySet wanted_encodings() const override { return {}; }
  void publish(const FrameRef&) override {}
};

// A subscriber's Hello asks for its key's buffers; they are made on the pool keeper's thread,
// which then says so, and not on the thread that asked (a publish thread serving others).
TEST(Pipeline, MakesTheBuffersARequestAsksForOnItsOwnThread) {
  const SubjectModel subject = build_subject(read_capture(test::source_path("replay_data/cmu/85_02.c3d")), {});
  const DeformationModel deformation = one_part_over(subject);
  Metrics metrics;
  FrameMailbox mailbox(subject.marker_count());
  NoConsumer consumer;
  // Before the pipeline, so that they outlive its keeper's thread, which calls back into them.
  const StreamKey key = stream_key(subscriber::kFrameNormals, subscriber::kVersion2);
  std::mutex mutex;
  std::condition_variable told;
  std::optional<std::thread::id> made_on;
  Pipeline pipeline(subject, &deformation, PipelineOptions{}, mailbox, consumer, metrics);
  pipeline.set_encoding_ready_callback([&](StreamKey ready) {
    EXPECT_EQ(ready, key);
    std::lock_guard lock(mutex);
    made_on = std::this_thread::get_id();
    told.notify_one();
  });
  EXPECT_FALSE(pipeline.encoding_ready(key));

  pipeline.request_encoding(key);
  std::unique_lock lock(mutex);
  ASSERT_TRUE(told.wait_for(lock, std::chrono::seconds(30), [&] { return made_on.has_value(); })) << "never made";
  EXPECT_NE(*made_on, std::this_thread::get_id());
  EXPECT_TRUE(pipeline.encoding_ready(key));
  EXPECT_EQ(metrics.frame_buffers_allocated.load(), pipeline.pool_frames()) << "one buffer per pooled frame";
  EXPECT_FALSE(pipeline.encoding_ready(stream_key(0, subscriber::kVersion2))) << "another key is not made with it";
}

// Takes the float positions with normals and markers, and the parameters; keeps each frame's
// number and whether every float of its messages is finite.
class RecordingConsumer : public FrameConsumer {
 public:
  StreamKeySet wanted_encodings() const override {
    StreamKeySet keys;
    keys.add(kFloats);
    keys.add(kParameters);
    return keys;
  }
  void publish(const FrameRef& frame) override {
    bool finite = true;
    for (const StreamKey key : {kFloats, kParameters}) {
      const std::span<const unsigned char> message = frame->message(key);
      if (message.size() < subscriber::kHeaderBytes) continue;
      const subscriber::Frame decoded = subscriber::decode_frame(message.subspan(subscriber::kHeaderBytes), subscriber::kVersion2);
      for (const std::vector<float>* values : {&decoded.positions, &decoded.normals, &decoded.markers})
        for (float v : *values) finite = finite && std::isfinite(v);
      const std::span<const unsigned char> block = decoded.coded_positions;  // the parameters
      for (size_t i = 8; i + 4 <= block.size(); i += 4) {
        float v;
        std::memcpy(&v, block.data() + i, 4);
        finite = finite && std::isfinite(v);
      }
    }
    std::lock_guard lock(mutex);
    frames.push_back(frame->frame_number);
    all_finite = all_finite && finite;
  }
  static inline const StreamKey kFloats = stream_key(subscriber::kFrameNormals | subscriber::kFrameMarkers, subscriber::kVersion2);
  static inline const StreamKey kParameters = stream_key(subscriber::kFrameParameters | subscriber::kFrameMarkers, subscriber::kVersion2);
  std::mutex mutex;
  std::vector<uint32_t> frames;
  bool all_finite = true;
};

// Source values the router would refuse, given to the pipeline directly (every marker at 1e39
// mm: infinite as a float): the frame is counted and never encoded; the frames before it go out,
// all finite. (Before, it went out with infinite markers and parameters.)
TEST(Pipeline, AFrameThatIsNotFiniteIsCountedAndNotEncoded) {
  const SubjectModel subject = build_subject(read_capture(test::source_path("replay_data/cmu/85_02.c3d")), {});
  const Capture take = read_capture(test::source_path("replay_data/cmu/85_12.c3d"));
  const DeformationModel deformation = one_part_over(subject);
  Metrics metrics;
  FrameMailbox mailbox(subject.marker_count());
  RecordingConsumer consumer;
  Pipeline pipeline(subject, &deformation, PipelineOptions{}, mailbox, consumer, metrics);
  pipeline.prepare_encoding(RecordingConsumer::kFloats);
  pipeline.prepare_encoding(RecordingConsumer::kParameters);
  pipeline.start();
  constexpr int kBad = 10;
  for (int f = 0; f <= kBad; ++f) {
    MarkerFrame& frame = mailbox.writable();
    frame.clear();
    frame.frame_number = static_cast<uint32_t>(f);
    frame.source_rate_hz = take.rate_hz;
    for (int m = 0; m < subject.marker_count(); ++m) frame.labelled[m] = take.at(f, m);
    if (f == kBad)
      for (Vec3& p : frame.labelled) p = Vec3(1e39, 0, 0);  // every marker: none for the filler to fill from
    mailbox.post(1);
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (metrics.frames_processed.load() < static_cast<uint64_t>(f + 1) && std::chrono::steady_clock::now() < give_up)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (metrics.bad_input("non_finite_frame") == 0 && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  pipeline.stop();
  EXPECT_EQ(metrics.bad_input("non_finite_frame"), 1u);
  std::lock_guard lock(consumer.mutex);
  EXPECT_TRUE(consumer.all_finite);
  std::vector<uint32_t> expected(kBad);
  for (int f = 0; f < kBad; ++f) expected[static_cast<size_t>(f)] = static_cast<uint32_t>(f);
  EXPECT_EQ(consumer.frames, expected);
}

}  // namespace
}  // namespace skinstream::server
