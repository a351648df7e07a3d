#include "server/ingest/vicon_source.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iterator>
#include <utility>

#include "protocol/vicon/vicon_packet_framer.h"
#include "protocol/vicon/vicon_packet_writer.h"
#include "server/ingest/source_lifecycle.h"
#include "server/ingest/source_reconnection.h"
#include "server/system_clock.h"

namespace skinstream::server {
namespace {

namespace type = vicon::object_type;

uint64_t marker_key(uint32_t subject_id, uint32_t marker_id) {
  return (static_cast<uint64_t>(subject_id) << 32) | marker_id;
}

// The types this client reads; the answer to ObjectEnums is their intersection with the offer.
constexpr uint32_t kWantedTypes[] = {type::StreamInfo,      type::SubjectInfo, type::FrameInfo, type::LabeledRecons,
                                     type::UnlabeledRecons, type::Timecode,    type::Contents};

// Bytes asked of the socket per read: several frames of 350 markers, so a backlog drains in few reads.
constexpr size_t kReadBytes = 64 * 1024;

// Unknown object types reported by name, at most.
constexpr size_t kRememberedTypes = 64;

// The SDK's timecode standards: PAL 0, NTSC 1, NTSCDrop 2, Film 3, NTSCFilm 4, ATSC 5.
SourceTimecode timecode_of(const vicon::Timecode& in) {
  struct Standard {
    float rate;
    bool drop;
  };
  static constexpr Standard kStandards[] = {{25.0f, false}, {30000.0f / 1001.0f, false}, {30000.0f / 1001.0f, true},
                                            {24.0f, false}, {24000.0f / 1001.0f, false}, {30.0f, false}};
  SourceTimecode out;
  if (in.standard >= std::size(kStandards)) return out;  // none: not valid
  out.valid = true;
  out.hours = in.hours;
  out.minutes = in.minutes;
  out.seconds = in.seconds;
  out.frames = in.frames;
  out.subframe = in.subframes;
  out.subframes_per_frame = in.subframes_per_frame;
  out.rate_hz = kStandards[in.standard].rate;
  out.drop_frame = kStandards[in.standard].drop;
  out.field = in.field_flag != 0;
  return out;
}

}  // namespace

// ---------------------------------------------------------------- ViconFrameAssembler

ViconFrameAssembler::ViconFrameAssembler(SourceSink& sink, const vicon::DescriptionLimits& limits) : sink_(sink), limits_(limits) {
  labeled_.reserve(512);
  unlabeled_.reserve(256);
  frame_.unlabelled.reserve(256);
  frame_.unlabelled_ids.reserve(256);
}

void ViconFrameAssembler::reset() {
  frame_period_ticks_ = 0;
  saw_object_enums_ = false;
  offered_.types.clear();
  // Until the new connection lists its subjects, there are none.
  subject_bytes_.clear();
  label_slots_.clear();
  frame_.subjects.clear();
  frame_.labelled.clear();
  ++frame_.structure_version;
  reported_unknown_marker_ = false;
}

bool ViconFrameAssembler::update_subjects(const std::vector<vicon::ObjectView>& objects, std::string& out_error) {
  subject_bytes_scratch_.clear();
  bool listed = false;  // this packet says which subjects there are
  for (const vicon::ObjectView& o : objects) {
    if (o.type == type::StreamInfo) listed = true;
    if (o.type != type::SubjectInfo) continue;
    listed = true;
    const auto length = static_cast<uint32_t>(o.payload.size());
    const auto* raw = reinterpret_cast<const unsigned char*>(&length);
    subject_bytes_scratch_.insert(subject_bytes_scratch_.end(), raw, raw + 4);
    subject_bytes_scratch_.insert(subject_bytes_scratch_.end(), o.payload.begin(), o.payload.end());
  }
  // Unchanged (the same bytes, or a packet that does not list the subjects): nothing to redo.
  if (!listed || subject_bytes_scratch_ == subject_bytes_) return true;

  std::vector<SourceSubject> subjects;
  std::vector<std::pair<uint64_t, uint64_t>> slots;
  for (const vicon::ObjectView& o : objects) {
    if (o.type != type::SubjectInfo) continue;
    vicon::SubjectInfo info;
    if (!vicon::decode(o.payload, info, out_error, limits_)) return false;
    SourceSubject& subject = subjects.emplace_back();
    subject.name = std::move(info.name);
    for (const vicon::SubjectMarker& m : info.markers) {
      slots.emplace_back(marker_key(info.subject_id, m.marker_id), (static_cast<uint64_t>(subjects.size() - 1) << 32) | subject.labels.size());
      subject.labels.push_back(m.name);
    }
  }
  std::sort(slots.begin(), slots.end());
  label_slots_ = std::move(slots);
  frame_.subjects = std::move(subjects);
  frame_.labelled.resize(frame_.subjects.size());
  for (size_t s = 0; s < frame_.subjects.size(); ++s) frame_.labelled[s].assign(frame_.subjects[s].labels.size(), missing_point());
  ++frame_.structure_version;
  subject_bytes_.swap(subject_bytes_scratch_);
  return true;
}

void ViconFrameAssembler::add_unlabelled(const std::array<double, 3>& position, uint32_t trajectory_id) {
  frame_.unlabelled.emplace_back(position[0], position[1], position[2]);
  frame_.unlabelled_ids.push_back(trajectory_id <= static_cast<uint32_t>(INT32_MAX) ? static_cast<int>(trajectory_id) : -1);
}

ViconFrameAssembler::Result ViconFrameAssembler::handle(const std::vector<vicon::ObjectView>& objects,
                                                        int64_t receive_time_ns, std::string& out_error) {
  for (const vicon::ObjectView& o : objects) {
    if (o.type == type::ObjectEnums) {
      if (!vicon::decode(o.payload, offered_, out_error)) return Result::Malformed;
      saw_object_enums_ = true;
    } else if (o.type == type::StreamInfo) {
      vicon::StreamInfo info;
      if (!vicon::decode(o.payload, info, out_error)) return Result::Malformed;
      frame_period_ticks_ = info.frame_period_ticks;
    }
  }
  if (!update_subjects(objects, out_error)) return Result::Malformed;

  for (std::vector<Vec3>& labels : frame_.labelled) std::fill(labels.begin(), labels.end(), missing_point());
  frame_.unlabelled.clear();
  frame_.unlabelled_ids.clear();
  frame_.timecode = {};
  bool has_frame = false;
  uint32_t frame_id = 0;
  for (const vicon::ObjectView& o : objects) {
    switch (o.type) {
      case type::FrameInfo: {
        vicon::FrameInfo info;
        if (!vicon::decode(o.payload, info, out_error)) return Result::Malformed;
        frame_id = info.frame_id;
        has_frame = true;
        break;
      }
      case type::LabeledRecons: {
        if (!vicon::decode(o.payload, labeled_, out_error)) return Result::Malformed;
        for (const vicon::LabeledRecon& r : labeled_) {
          const uint64_t key = marker_key(r.subject_id, r.marker_id);
          const auto it = std::lower_bound(label_slots_.begin(), label_slots_.end(), std::make_pair(key, uint64_t{0}));
          if (it == label_slots_.end() || it->first != key) {
            if (!std::exchange(reported_unknown_marker_, true))
              sink_.on_bad_input("unknown_marker_id", "a labelled marker (subject id " + std::to_string(r.subject_id) + ", marker id " +
                                                          std::to_string(r.marker_id) +
                                                          ") that SubjectInfo does not list: passed on as unlabelled (reported once)");
            add_unlabelled(r.position, r.trajectory_id);
            continue;
          }
          frame_.labelled[it->second >> 32][it->second & 0xFFFFFFFFu] = Vec3(r.position[0], r.position[1], r.position[2]);
        }
        break;
      }
      case type::UnlabeledRecons: {
        if (!vicon::decode(o.payload, unlabeled_, out_error)) return Result::Malformed;
        for (const vicon::UnlabeledRecon& r : unlabeled_) add_unlabelled(r.position, r.trajectory_id);
        break;
      }
      case type::Timecode: {
        vicon::Timecode timecode;
        if (!vicon::decode(o.payload, timecode, out_error)) return Result::Malformed;
        frame_.timecode = timecode_of(timecode);
        break;
      }
      case type::ObjectEnums:
      case type::StreamInfo:
      case type::SubjectInfo:
      case type::Contents:
      case type::Ping:
        break;
      default:
        // Each unknown type once, remembering a few: a source sending many kinds is only counted.
        if (reported_types_.size() < kRememberedTypes && reported_types_.insert(o.type).second)
          sink_.on_bad_input("unknown_object", "skipping Vicon object type " + std::to_string(o.type) + " (reported once)");
        break;
    }
  }
  if (!has_frame) return Result::NoFrame;
  frame_.frame_number = frame_id + 1;  // as the Vicon SDK numbers frames
  frame_.rate_hz = vicon::rate_from_period(frame_period_ticks_);
  // ticks / 135 MHz in ns = ticks * 200 / 27, split so that a long take cannot overflow.
  const int64_t ticks = static_cast<int64_t>(frame_id) * frame_period_ticks_;
  frame_.source_time_ns = ticks / 27 * 200 + ticks % 27 * 200 / 27;
  frame_.receive_time_ns = receive_time_ns;
  return Result::Frame;
}

// ---------------------------------------------------------------- ViconSource

struct ViconSource::State : std::enable_shared_from_this<ViconSource::State> {
  State(asio::io_context& io_context, ViconSourceOptions opts, SourceSink& frame_sink)
      : io(io_context),
        options(std::move(opts)),
        sink(frame_sink),
        assembler(frame_sink, options.limits),
        socket(io),
        resolver(io),
        watchdog(io),
        reconnection(io, sink, options.initial_backoff_seconds, options.max_backoff_seconds),
        framer(vicon::kMaxPacketLength, options.limits) {
    pull_request = vicon::encode_packet(vicon::RequestFrame{false});
    out_pending.reserve(256);
    out_inflight.reserve(256);
  }

  asio::io_context& io;
  ViconSourceOptions options;
  SourceSink& sink;
  ViconFrameAssembler assembler;
  tcp::socket socket;
  tcp::resolver resolver;
  asio::steady_timer watchdog;  // the handshake's and the stream's silences
  SourceReconnection reconnection;
  std::chrono::steady_clock::time_point connected_at, last_frame;
  vicon::PacketFramer framer;
  std::vector<unsigned char> pull_request;
  std::vector<unsigned char> out_pending;   // bytes waiting for the write in flight
  std::vector<unsigned char> out_inflight;
  bool writing = false;
  bool handshake_sent = false;
  uint64_t generation = 0;  // bumps on every new connection: stale handlers see a different one
  std::atomic<bool> stopped{false};

  std::string where() const { return options.host + ":" + std::to_string(options.port); }

  void connect() {
    if (stopped) return;
    const uint64_t gen = ++generation;
    framer.reset();
    // A read plus the partial packet a burst can leave behind it: sized and touched now, so a
    // backlog after a stall neither reallocates nor faults in fresh pages on the io thread.
    framer.reserve(2 * kReadBytes);
    assembler.reset();
    handshake_sent = false;
    writing = false;
    out_pending.clear();
    connected_at = std::chrono::steady_clock::now();
    watch(gen);
    resolver.async_resolve(options.host, std::to_string(options.port),
                           [self = shared_from_this(), gen](const boost::system::error_code& ec,
                                                            const tcp::resolver::results_type& results) {
                             if (self->stopped || gen != self->generation) return;
                             if (ec) return self->fail(gen, "cannot resolve " + self->where() + ": " + ec.message());
                             asio::async_connect(self->socket, results,
                                                 [self, gen](const boost::system::error_code& ec2, const tcp::endpoint&) {
                                                   if (self->stopped || gen != self->generation) return;
                                                   if (ec2)
                                                     return self->fail(gen, "cannot connect to " + self->where() + ": " +
                                                                                ec2.message());
                                                   boost::system::error_code ignored;
                                                   self->socket.set_option(tcp::no_delay(true), ignored);
                                                   self->socket.non_blocking(true, ignored);
                                                   self->read(gen);
                                                 });
                           });
  }

  void read(uint64_t gen) {
    const auto room = framer.prepare(kReadBytes);
    socket.async_read_some(asio::buffer(room.data(), room.size()),
                           [self = shared_from_this(), gen](const boost::system::error_code& ec, size_t n) {
                             self->on_read(gen, ec, n);
                           });
  }

  void on_read(uint64_t gen, const boost::system::error_code& ec, size_t n) {
    if (stopped || gen != generation) return;
    if (ec) {
      fail(gen, (ec == asio::error::eof ? std::string("the server closed the connection")
                                        : "connection lost: " + ec.message()) +
                    " (" + where() + ")");
      return;
    }
    framer.commit(n);
    vicon::Bytes packet;
    for (;;) {
      const auto status = framer.next(packet);
      if (status == vicon::PacketFramer::Status::NeedMore) break;
      if (status == vicon::PacketFramer::Status::Error) {
        sink.on_bad_input("malformed_packet", framer.error());
        fail(gen, "malformed packet from " + where() + ": " + framer.error());
        return;
      }
      std::string error;
      const auto result = assembler.handle(framer.objects(), system_now_ns(), error);
      if (stopped) return;
      if (result == ViconFrameAssembler::Result::Malformed) {
        sink.on_bad_input("malformed_packet", error);
        fail(gen, "malformed packet from " + where() + ": " + error);
        return;
      }
      if (!handshake_sent && assembler.saw_object_enums()) send_handshake(gen);
      if (result == ViconFrameAssembler::Result::Frame) {
        last_frame = std::chrono::steady_clock::now();
        reconnection.frame_arrived(where());
        sink.on_frame(assembler.frame());
        if (stopped) return;
        if (options.mode == ViconSourceOptions::Mode::ClientPull) send(gen, pull_request);
      }
    }
    read(gen);
  }

  void send_handshake(uint64_t gen) {
    handshake_sent = true;
    last_frame = std::chrono::steady_clock::now();  // the stall time runs from here
    vicon::ObjectEnums wanted;
    for (uint32_t t : kWantedTypes)
      if (std::find(assembler.offered().types.begin(), assembler.offered().types.end(), t) !=
          assembler.offered().types.end())
        wanted.types.push_back(t);
    std::sort(wanted.types.begin(), wanted.types.end());
    const bool push = options.mode == ViconSourceOptions::Mode::ServerPush;
    send(gen, vicon::encode_packet(wanted, vicon::RequestFrame{push}));
  }

  // A request is a few bytes into an empty send buffer: written at once without an asynchronous
  // operation (which would allocate per frame next to the pending read); queued only if it cannot.
  void send(uint64_t gen, const std::vector<unsigned char>& bytes) {
    size_t written = 0;
    if (!writing && out_pending.empty()) {
      boost::system::error_code ec;
      written = socket.write_some(asio::buffer(bytes), ec);
      if (ec == asio::error::would_block || ec == asio::error::try_again) {
        written = 0;
      } else if (ec) {
        fail(gen, "cannot send to " + where() + ": " + ec.message());
        return;
      }
    }
    out_pending.insert(out_pending.end(), bytes.begin() + static_cast<long>(written), bytes.end());
    flush(gen);
  }

  void flush(uint64_t gen) {
    if (writing || out_pending.empty()) return;
    writing = true;
    out_inflight.swap(out_pending);
    out_pending.clear();
    asio::async_write(socket, asio::buffer(out_inflight),
                      [self = shared_from_this(), gen](const boost::system::error_code& ec, size_t) {
                        if (self->stopped || gen != self->generation) return;
                        self->writing = false;
                        self->out_inflight.clear();
                        if (ec) return self->fail(gen, "cannot send to " + self->where() + ": " + ec.message());
                        self->flush(gen);
                      });
  }

  // No ObjectEnums within handshake_timeout of connecting (a server that accepts and says
  // nothing), or no frame for stall_timeout after it (one that went silent with its connection
  // open): the connection is left and retried. Checked ten times a second.
  void watch(uint64_t gen) {
    watchdog.expires_after(std::chrono::milliseconds(100));
    watchdog.async_wait([self = shared_from_this(), gen](const boost::system::error_code& ec) {
      if (ec || self->stopped || gen != self->generation) return;
      using std::chrono::duration_cast;
      using std::chrono::milliseconds;
      const auto now = std::chrono::steady_clock::now();
      if (!self->handshake_sent && now - self->connected_at > self->options.handshake_timeout)
        return self->fail(gen, "no ObjectEnums from " + self->where() + " within " +
                                   std::to_string(self->options.handshake_timeout.count()) + " ms of connecting");
      if (self->handshake_sent && self->options.stall_timeout.count() > 0 && now - self->last_frame > self->options.stall_timeout)
        return self->fail(gen,
                          "stalled: no frame from " + self->where() + " for " +
                              std::to_string(duration_cast<milliseconds>(now - self->last_frame).count()) +
                              " ms with the connection open; reconnecting",
                          SourceState::Stalled);
      self->watch(gen);
    });
  }

  void close_sockets() {
    boost::system::error_code ignored;
    watchdog.cancel();
    resolver.cancel();
    socket.shutdown(tcp::socket::shutdown_both, ignored);
    socket.close(ignored);
  }

  void fail(uint64_t gen, const std::string& reason, SourceState reported = SourceState::Disconnected) {
    fail_connection(shared_from_this(), gen, reason, reported);
  }
};

ViconSource::ViconSource(asio::io_context& io, ViconSourceOptions options, SourceSink& sink)
    : state_(std::make_shared<State>(io, std::move(options), sink)) {}

ViconSource::~ViconSource() { stop(); }

void ViconSource::start() { start_source(state_); }
void ViconSource::stop() { stop_source(state_); }

}  // namespace skinstream::server
