#pragma once
// skinstream's C++ client library: subscribe to a skinstreamd and receive each frame of a
// subject's deforming mesh as vertex positions and normals, however the daemon sends them
// (float, quantised, compressed, or as the frame's deformation parameters, which the library
// evaluates here with the daemon's own code and numbers). One Subscriber is one TCP
// connection, read on the thread that calls next(). Protocol: docs/subscriber-protocol.md.
//
//   skinstream::client::Subscriber sub({.host = "stage-pc", .encoding = skinstream::client::Encoding::Parameters});
//   skinstream::client::Frame frame;
//   while (sub.next(frame, std::chrono::seconds(1)))
//     upload(frame.positions, frame.normals);  // 3 floats per vertex, mm; sub.mesh().indices
//
// Errors (no daemon, refused, a daemon that goes away or falls silent, bytes that break the
// protocol) throw skinstream::client::Error with a one-line reason, the daemon's own words in it
// made printable; make a new Subscriber to try again. From a multicast group, bad datagrams are
// counted instead (multicast_stats()): anyone can send to it.

#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace skinstream::client {

// How the daemon sends positions (the subscriber protocol's encodings).
enum class Encoding : uint32_t { Float = 0, Quantised = 1, Compressed = 2, Parameters = 3 };
const char* to_string(Encoding encoding);
// "float", "quantised", "compressed", "parameters"; throws std::invalid_argument otherwise.
Encoding encoding_from_string(const std::string& name);

// Frames from the daemon's multicast group instead of the TCP connection (the daemon's
// --multicast; docs/subscriber-protocol.md, "Multicast"): the Subscriber takes MeshInfo and the
// Model from the daemon's offer on the group's next port (what it sends round and round, so
// that receivers joining together take one copy), or, when none is complete within offer_wait
// (no offer, or its datagrams lost), over TCP from host:port, closing that connection after; it
// then reads the parameters of every frame from the group. A lost datagram costs the frame it carried; next()
// never waits for it, and gives the newest complete frame (a reader slower than the stream skips frames
// instead of falling behind by what the socket buffer holds). Anyone on the LAN can send to the group: with
// the daemon's key (its multicast_key_file) only datagrams signed with it are taken; without
// one, a forged or stale datagram costs at most 100 ms of frames. Frames of another Model than
// the one fetched are counted and skipped; when only such frames came for a second, the
// daemon's subject changed, and the new Model is taken again (from the offer, else over TCP).
struct MulticastOptions {
  std::string group{};                       // IPv4 multicast address; empty: frames over TCP
  uint16_t port = 0;
  std::string interface_address = "0.0.0.0";  // this host's address to join on (name the stage network's)
  uint32_t stream_id = 0;                    // the subject's stream (0: the daemon's first)
  std::chrono::milliseconds window{50};      // a frame's datagrams must all arrive within it
  std::string key{};                         // the daemon's multicast key (at least 16 bytes); empty: none checked
  bool offer = true;                         // take MeshInfo and the Model from the offer (port + 1) first
  std::chrono::milliseconds offer_wait{3000};  // the offer complete within this, else over TCP
};

// What arrived from the multicast group so far.
struct MulticastStats {
  uint64_t datagrams = 0;           // of this stream
  uint64_t frames_completed = 0;
  uint64_t frames_lost = 0;         // the daemon sent them and they never completed here
  uint64_t frames_incomplete = 0;   // of those, frames some of whose datagrams arrived
  uint64_t datagrams_rejected = 0;  // broke the protocol (last_error says how)
  uint64_t datagrams_other_stream = 0;
  uint64_t datagrams_late = 0;      // for a frame already complete or given up
  uint64_t datagrams_duplicate = 0;
  uint64_t frames_superseded = 0;   // complete, and a newer one was complete before next() took it
  uint64_t messages_rejected = 0;   // whole messages that broke the protocol
  std::string last_error{};         // one line, of the last datagram or message rejected
  uint64_t datagrams_out_of_window = 0;    // sequences far from the stream's: forged, or a sender that started again
  uint64_t datagrams_unauthenticated = 0;  // with a key: datagrams without its tag (of the rejected)
  uint64_t resyncs = 0;                    // the stream taken up afresh after 100 ms without a frame
  uint64_t frames_other_model = 0;         // complete frames of another Model than the one fetched, skipped
  uint64_t model_fetches = 0;              // the Model fetched again (the daemon's subject changed)
  // The offer: MeshInfo and the Model from the group.
  uint64_t offer_datagrams = 0;  // of this stream, taken (while this receiver listened to the offer)
  uint64_t offers_taken = 0;     // complete, and MeshInfo and the Model taken from them
  uint64_t offers_rejected = 0;  // complete, and refused (last_error says why): the next round is tried
  uint64_t offer_timeouts = 0;   // none taken within offer_wait: MeshInfo and the Model fetched over TCP
};

struct Options {
  std::string host = "127.0.0.1";
  uint16_t port = 8481;
  Encoding encoding = Encoding::Parameters;
  bool normals = true;       // vertex normals (with parameters: computed here from the positions)
  bool markers = false;      // the filled markers and their status
  bool mesh = true;          // false: markers only, no vertices
  bool paced = false;        // acknowledge each frame: at most 2 in flight (for slow readers)
  bool evaluate = true;      // parameters: evaluate them into vertices (false: parameters only)
  // Protocol 2: MeshInfo and the Model come packed (deflated), about 2.8 times fewer bytes to
  // wait for as the subscriber joins; false asks for them plain.
  bool packed = true;
  // false: frames carry their numbers, times and markers only; positions and normals stay empty
  // and nothing is decoded (a load generator that must not spend the CPU it measures).
  bool decode = true;
  std::string subject{};     // the capture system's subject name; empty: the daemon's first
  std::string token{};       // the daemon's shared token, when it has one
  int protocol_version = 2;  // 1 speaks to a daemon older than version 2 (float or quantised)
  std::chrono::milliseconds connect_timeout{5000};
  // The daemon says something at least every second (Status); silent this long over TCP (gone,
  // or a message cut short), it is given up with an Error. 0: wait for ever.
  std::chrono::milliseconds silence_timeout{10000};
  // The largest mesh and marker set taken: a MeshInfo announcing more is an Error, before
  // anything is made for it.
  uint32_t max_vertices = 4'000'000;
  uint32_t max_markers = 4096;
  MulticastOptions multicast{};  // group set: frames from it (encoding parameters, protocol 2)
};

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What MeshInfo says of the subject (valid once has_mesh()).
struct Mesh {
  std::string subject;
  Encoding encoding = Encoding::Float;  // what the daemon serves (it says why in Status when not what was asked)
  uint32_t vertex_count = 0;
  std::vector<uint32_t> indices;         // 3 per triangle, counter-clockwise from outside
  std::vector<uint8_t> dominant_part;    // per vertex, 255 = none (for colouring the segmentation)
  uint32_t part_count = 0;
  std::vector<std::string> marker_names;
  std::vector<uint32_t> marker_triangles;  // 3 per triangle of the marker surface
  float source_rate_hz = 0.0f;
};

struct Timecode {
  bool valid = false;
  int hours = 0, minutes = 0, seconds = 0, frames = 0;
  int subframe = 0, subframes_per_frame = 0;
  float rate_hz = 0.0f;
  bool drop_frame = false;
};

// Marker status values (Frame::marker_status).
enum class MarkerStatus : uint8_t { Measured = 0, Relabelled = 1, FilledByPca = 2, FilledRigidly = 3, Held = 4 };

// One frame. The spans point into the Subscriber and stay valid until its next call to next().
struct Frame {
  uint32_t frame_number = 0;
  int64_t source_time_ns = 0;   // capture time, from the source
  int64_t receive_time_ns = 0;  // the daemon received it (system clock, ns since the epoch)
  int64_t publish_time_ns = 0;  // the daemon handed it to the publishers
  int64_t arrival_time_ns = 0;  // its last byte arrived here
  int64_t ready_time_ns = 0;    // decoded (and evaluated) here: when the renderer can use it
  Timecode timecode;
  uint16_t markers_filled = 0, markers_relabelled = 0;
  uint32_t pipeline_dropped = 0;    // frames the daemon's pipeline dropped so far
  uint32_t subscriber_dropped = 0;  // frames dropped for this subscriber so far
  size_t message_bytes = 0;         // the Frame message's size on the wire
  bool key_frame = false;           // compressed: a key frame
  std::span<const float> positions;  // 3 per vertex, mm (empty: markers only, or parameters not evaluated)
  std::span<const float> normals;    // 3 per vertex, unit (empty when not asked for)
  std::span<const float> markers;    // 3 per marker, mm, subject order
  std::span<const uint8_t> marker_status;  // MarkerStatus per marker
};

// What the daemon last said of its source (Status messages).
struct SourceStatus {
  enum class State { Connecting = 0, Streaming = 1, Disconnected = 2, Finished = 3, Refused = 4 };
  State state = State::Connecting;
  float source_rate_hz = 0.0f;
  uint64_t frames_received = 0, frames_published = 0;
  std::string detail;
  std::string subject;
  bool subject_present = false;
};

class Subscriber {
 public:
  // Connects and sends Hello; throws Error when the daemon cannot be reached. With multicast and
  // its offer, it only joins the group: the daemon is reached over TCP only if the offer does not
  // come (next() then throws Error when it cannot be reached).
  explicit Subscriber(Options options);
  ~Subscriber();
  Subscriber(const Subscriber&) = delete;
  Subscriber& operator=(const Subscriber&) = delete;

  // Reads until the next frame is ready and fills `frame`; false when none came within
  // `timeout`. Delta frames of a compressed stream that joined between key frames are skipped
  // (counted in frames_skipped()). A Frame message that breaks the protocol on its own (a value
  // that is not finite, a block of the wrong size) is skipped too, counted in frames_rejected()
  // with the reason in last_rejection(): the next frame is as good as ever. Throws Error when
  // the daemon refuses this subscriber, closes the connection, or sends bytes that break the
  // protocol otherwise.
  bool next(Frame& frame, std::chrono::milliseconds timeout);

  bool has_mesh() const;
  const Mesh& mesh() const;
  const SourceStatus& status() const;
  const Options& options() const;
  uint64_t frames_skipped() const;  // compressed deltas without their key
  // MeshInfo messages taken: more than one when the daemon swapped the subject's model (a live
  // calibration: mesh() and the Model are then the new ones) or a new Hello changed the encoding.
  uint64_t meshes_received() const;
  uint64_t frames_rejected() const;  // Frame messages that broke the protocol, skipped
  std::string last_rejection() const;  // one line: why the last of them was skipped
  uint64_t bytes_received() const;
  // Parameters: the size of the Model message (bytes, header included; 0 before it came).
  size_t model_bytes() const;
  // Parameters: the last frame's raw parameters (floats as sent: per part A 3x9, R 3x3, d, flag;
  // then 3 RBF weights per member), for renderers that evaluate on their GPU (Options::evaluate
  // false). Empty for other encodings.
  std::span<const unsigned char> parameter_block() const;
  // Parameters: the Model message's payload, for the same renderers.
  std::span<const unsigned char> model_payload() const;
  // Multicast: what arrived from the group (all zero without Options::multicast).
  MulticastStats multicast_stats() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace skinstream::client
