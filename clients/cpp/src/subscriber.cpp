#include <algorithm>
#include <cstring>
#include <optional>

#include "core/deform/mesh_evaluator.h"
#include "multicast_socket.h"
#include "protocol/printable_text.h"
#include "protocol/subscriber/compressed_vertices.h"
#include "protocol/subscriber/datagram_reassembler.h"
#include "protocol/subscriber/finite_values.h"
#include "protocol/subscriber/frame_parameters.h"
#include "protocol/subscriber/offer_content.h"
#include "protocol/subscriber/offer_reassembler.h"
#include "protocol/subscriber/packed_message.h"
#include "protocol/subscriber/subscriber_model.h"
#include "protocol/subscriber/subscriber_stream.h"
#include "skinstream/client.h"
#include "tcp_connection.h"

namespace skinstream::client {
namespace wire = skinstream::subscriber;

namespace {

// memcpy for spans that may be empty: an empty span's data() may be null, and memcpy's pointers
// must be valid even for 0 bytes (a markers-only stream has no vertices, a mesh stream may have
// no markers).
void copy_bytes(void* to, const void* from, size_t bytes) {
  if (bytes > 0) std::memcpy(to, from, bytes);
}

int64_t wall_clock_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// Up to 1 MiB a read: a 53,500-vertex float frame (640 kB) in one or two reads.
constexpr size_t kReadBytes = 1 << 20;
// The largest UDP datagram: one that breaks the protocol's 1,400 is read whole and rejected.
constexpr size_t kDatagramReadBytes = 65536;

}  // namespace

const char* to_string(Encoding encoding) { return wire::to_string(static_cast<wire::Encoding>(encoding)); }

Encoding encoding_from_string(const std::string& name) {
  for (uint32_t e = 0; e < wire::kEncodingCount; ++e)
    if (name == wire::to_string(static_cast<wire::Encoding>(e))) return static_cast<Encoding>(e);
  throw std::invalid_argument("unknown encoding \"" + name + "\" (float, quantised, compressed or parameters)");
}

struct Subscriber::State {
  Options options;
  uint16_t version = wire::kVersion2;
  std::optional<TcpConnection> connection;
  wire::StreamDecoder decoder;
  Mesh mesh;
  bool has_mesh = false;
  SourceStatus status;
  uint64_t skipped = 0;
  uint64_t meshes_received = 0;  // MeshInfo messages taken
  uint64_t rejected = 0;  // Frame messages that broke the protocol on their own
  std::string last_rejection;
  uint64_t bytes = 0;
  int64_t arrival_ns = 0;  // of the last bytes read
  std::chrono::steady_clock::time_point last_heard;  // bytes from the daemon over TCP (or connected)

  // Parameters.
  std::vector<unsigned char> model_payload;
  std::unique_ptr<MeshEvaluator> evaluator;
  FrameParameters parameters;
  std::vector<unsigned char> parameter_block;
  // Compressed.
  std::unique_ptr<wire::CompressedVertexDecoder> compressed;
  // Multicast: frames from the group once the Model came over TCP (then the connection closes).
  std::optional<MulticastSocket> group;
  std::optional<wire::DatagramReassembler> reassembler;
  std::vector<unsigned char> datagram;
  uint32_t model_id = 0;
  wire::Hello hello;  // what was asked, to fetch the Model again
  uint64_t frames_other_model = 0, model_fetches = 0;
  std::chrono::steady_clock::time_point other_model_since{}, last_own_frame{};
  std::vector<unsigned char> ready_message;  // the newest complete frame, not yet handed out
  int64_t ready_arrival_ns = 0;
  uint64_t superseded = 0;
  uint64_t messages_rejected = 0;
  std::string last_error;
  // The offer: MeshInfo and the Model from the group's next port, before the frames (and again
  // when the subject changed), until offer_deadline; then over TCP.
  std::optional<MulticastSocket> offer_socket;
  std::optional<wire::OfferReassembler> offer;
  std::chrono::steady_clock::time_point offer_deadline{};
  std::optional<uint32_t> wanted_model_id;  // after a change: the id the new frames carry
  uint64_t offers_taken = 0, offers_rejected = 0, offer_timeouts = 0;

  std::vector<float> positions, normals, markers;
  std::vector<uint8_t> marker_status;

  void on_mesh_info(std::span<const unsigned char> payload);
  void on_model(std::span<const unsigned char> payload);
  void on_status(std::span<const unsigned char> payload);
  // False when the frame cannot be shown (a compressed delta without its key).
  bool on_frame(std::span<const unsigned char> payload, Frame& frame);
  // Reads the TCP stream until a frame is ready (true), the deadline passes, or, with multicast,
  // the Model came and the connection was closed (false).
  bool read_connection(Frame& frame, std::chrono::steady_clock::time_point deadline);
  // Reads the group's datagrams until a frame is ready (true) or the deadline passes.
  bool read_group(Frame& frame, std::chrono::steady_clock::time_point deadline);
  // Listens to the offer until MeshInfo and the Model are taken from it, or (its wait over) a
  // TCP connection fetches them (true), or the deadline passes (false).
  bool read_offer(std::chrono::steady_clock::time_point deadline);
  // Takes MeshInfo and the Model from the group's offer, else over TCP.
  void listen_to_offer();
  // Decodes and evaluates ready_message into `frame` (false: it broke the protocol; counted).
  bool take_ready_message(Frame& frame);
  void reject(const std::string& what);
  // A complete group frame of another Model than ours: skipped; after a second of those alone,
  // the daemon's subject changed: MeshInfo and the Model are fetched again over TCP (true).
  bool other_model(uint32_t id, std::chrono::steady_clock::time_point now);
  void connect();  // to the daemon over TCP, with the Hello
};

// Frames of another Model alone for this long: the daemon's, not a forger's.
constexpr auto kModelChangeAfter = std::chrono::seconds(1);

Subscriber::Subscriber(Options options) : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.options = std::move(options);
  const Options& o = s.options;
  if (o.protocol_version != 1 && o.protocol_version != 2)
    throw std::invalid_argument("protocol version " + std::to_string(o.protocol_version) + " (this library speaks 1 and 2)");
  s.version = static_cast<uint16_t>(o.protocol_version);
  if (s.version == wire::kVersion1 && (o.encoding == Encoding::Compressed || o.encoding == Encoding::Parameters))
    throw std::invalid_argument(std::string("the ") + to_string(o.encoding) + " encoding needs protocol version 2");
  if (s.version == wire::kVersion1 && (!o.subject.empty() || !o.token.empty()))
    throw std::invalid_argument("a subject or a token needs protocol version 2");
  wire::Hello hello;
  hello.version = s.version;
  hello.wants = (o.normals ? wire::kWantNormals : 0) | (o.markers ? wire::kWantMarkers : 0) | (o.mesh ? 0 : wire::kWantNoMesh) |
                (o.paced ? wire::kWantPaced : 0);
  if (s.version == wire::kVersion1 && o.encoding == Encoding::Quantised) hello.wants |= wire::kWantQuantised;
  if (s.version == wire::kVersion2 && o.packed) hello.wants |= wire::kWantPacked;
  hello.encoding = static_cast<uint32_t>(o.encoding);
  hello.subject = o.subject;
  hello.token = o.token;
  if (!o.multicast.group.empty()) {
    if (s.version != wire::kVersion2 || o.encoding != Encoding::Parameters || o.paced || !o.mesh)
      throw std::invalid_argument("multicast carries the parameters of the mesh only: encoding parameters, protocol 2, not paced");
    wire::DatagramReassembler::Options reassembly{o.multicast.stream_id, o.multicast.window};
    if (!o.multicast.key.empty())
      reassembly.authenticator = std::make_shared<wire::DatagramAuthenticator>(
          std::span(reinterpret_cast<const unsigned char*>(o.multicast.key.data()), o.multicast.key.size()));
    // Joined first, so the group's datagrams wait in the socket while the Model comes.
    s.group.emplace(o.multicast.group, o.multicast.port, o.multicast.interface_address);
    s.reassembler.emplace(reassembly);
    s.datagram.resize(kDatagramReadBytes);
    s.ready_message.reserve(wire::kMaxDatagramMessageBytes);
    hello.wants &= ~(wire::kWantMarkers);  // the group's frames carry none
    if (o.multicast.offer) {
      wire::OfferReassembler::Options offer_options{.stream_id = o.multicast.stream_id,
                                                    .authenticator = reassembly.authenticator};
      s.offer.emplace(offer_options);
    }
  }
  s.hello = hello;
  if (s.offer)
    s.listen_to_offer();
  else
    s.connect();
}

void Subscriber::State::listen_to_offer() {
  const MulticastOptions& m = options.multicast;
  offer->restart();
  offer_socket.emplace(m.group, static_cast<uint16_t>(m.port + 1), m.interface_address);
  offer_deadline = std::chrono::steady_clock::now() + m.offer_wait;
}

void Subscriber::State::connect() {
  decoder = wire::StreamDecoder();
  connection.emplace(options.host, options.port, options.connect_timeout);
  connection->send_all(wire::encode_hello(hello));
  last_heard = std::chrono::steady_clock::now();
}

Subscriber::~Subscriber() = default;

bool Subscriber::next(Frame& frame, std::chrono::milliseconds timeout) {
  State& s = *state_;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  if (s.offer_socket && !s.read_offer(deadline)) return false;
  if (s.connection && s.read_connection(frame, deadline)) return true;
  return s.group && !s.connection && s.read_group(frame, deadline);
}

bool Subscriber::State::read_offer(std::chrono::steady_clock::time_point deadline) {
  for (;;) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= offer_deadline) {
      ++offer_timeouts;
      offer_socket.reset();
      wanted_model_id.reset();
      connect();
      return true;
    }
    if (now >= deadline) return false;
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(std::min(deadline, offer_deadline) - now);
    std::chrono::steady_clock::time_point arrival;
    const size_t n = offer_socket->receive(datagram, left, arrival);
    if (n == 0) continue;
    bytes += n;
    std::optional<wire::OfferReassembler::Offer> complete;
    try {
      complete = offer->add(std::span<const unsigned char>(datagram).first(n), arrival);
    } catch (const wire::DecodeError& e) {
      last_error = std::string("bad offer datagram: ") + e.what();  // counted by the reassembler
      continue;
    }
    if (!complete) continue;
    if (wanted_model_id && complete->header.model_id != *wanted_model_id) {
      offer->restart();  // the old subject's, still going round: the next edition is the new one's
      continue;
    }
    // Anyone on the LAN can send to the group: an offer that is not a subject's is counted, and
    // the next round tried.
    try {
      const wire::OfferContent content = wire::decode_offer(complete->bytes, complete->header.model_id);
      on_mesh_info(content.mesh_info.payload);
      on_model(content.model.payload);
    } catch (const wire::DecodeError& e) {
      ++offers_rejected;
      last_error = std::string("bad offer: ") + e.what();
      offer->restart();
      continue;
    } catch (const Error& e) {
      ++offers_rejected;
      last_error = std::string("bad offer: ") + e.what();
      offer->restart();
      continue;
    }
    ++offers_taken;
    model_id = complete->header.model_id;
    wanted_model_id.reset();
    offer_socket.reset();
    return true;
  }
}

bool Subscriber::State::read_connection(Frame& frame, std::chrono::steady_clock::time_point deadline) {
  State& s = *this;
  for (;;) {
    try {
      while (const std::optional<wire::RawMessage> message = s.decoder.next()) {
        if (message->version != s.version)
          throw Error("the daemon answered in protocol version " + std::to_string(message->version) + ", not " + std::to_string(s.version));
        wire::MessageType type = message->type;
        std::span<const unsigned char> payload = message->payload;
        wire::Unpacked unpacked;  // a Packed message's MeshInfo or Model
        if (type == wire::MessageType::Packed) {
          if (!(s.hello.wants & wire::kWantPacked))
            throw Error("the daemon sent a Packed message, which this subscriber did not ask for");
          unpacked = wire::decode_packed(payload);
          type = unpacked.type;
          payload = unpacked.payload;
        }
        switch (type) {
          case wire::MessageType::MeshInfo:
            s.on_mesh_info(payload);
            break;
          case wire::MessageType::Model:
            s.on_model(payload);
            if (s.group) {  // the frames come from the group from now on
              s.model_id = wire::model_id_of(s.model_payload);
              s.connection.reset();
              return false;
            }
            break;
          case wire::MessageType::Status: s.on_status(message->payload); break;
          case wire::MessageType::Frame: {
            // A frame that breaks the protocol on its own (its length framed it, so the stream
            // is still in step) is skipped and counted: the next one is as good as ever.
            bool ready = false;
            try {
              ready = s.on_frame(message->payload, frame);
            } catch (const wire::DecodeError& e) {
              ++s.rejected;
              s.last_rejection = std::string("frame skipped: ") + e.what();
            }
            // Paced: every Frame taken is acknowledged, a skipped one too (a compressed delta
            // without its key): the daemon sends nothing more while two wait for an Ack.
            if (s.options.paced && message->payload.size() >= sizeof(uint32_t)) {
              uint32_t number;
              std::memcpy(&number, message->payload.data(), sizeof number);
              s.connection->send_all(wire::encode_ack({number}, s.version));
            }
            if (ready) return true;
            break;
          }
          default:
            throw Error(std::string("unexpected ") + wire::to_string(type) + " message from the daemon");
        }
      }
    } catch (const wire::DecodeError& e) {
      throw Error(std::string("bad message from the daemon: ") + e.what());
    }
    const auto now = std::chrono::steady_clock::now();
    if (s.options.silence_timeout.count() > 0 && now - s.last_heard >= s.options.silence_timeout)
      throw Error("nothing from the daemon for " + std::to_string(s.options.silence_timeout.count()) +
                  " ms, and it says something every second: gone, or a message cut short (" + std::to_string(s.decoder.buffered()) +
                  " bytes of one came)");
    auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now);
    if (left.count() < 0) return false;
    if (s.options.silence_timeout.count() > 0)
      left = std::min(left, std::chrono::duration_cast<std::chrono::milliseconds>(s.last_heard + s.options.silence_timeout - now) +
                                std::chrono::milliseconds(1));
    const std::span<unsigned char> room = s.decoder.prepare(kReadBytes);
    const size_t n = s.connection->receive(room, left);
    s.decoder.commit(n);
    if (n > 0) s.last_heard = std::chrono::steady_clock::now();
    if (n == 0 && std::chrono::steady_clock::now() >= deadline) return false;
    s.bytes += n;
    s.arrival_ns = wall_clock_ns();
  }
}

bool Subscriber::State::read_group(Frame& frame, std::chrono::steady_clock::time_point deadline) {
  for (;;) {
    // The newest complete frame wins: once one is complete, the datagrams already waiting are
    // read too (without waiting), and a newer frame among them replaces it. A reader slower than
    // the stream so skips frames instead of falling behind by what the socket buffer holds.
    const bool have_one = !ready_message.empty();
    const auto now = std::chrono::steady_clock::now();
    const auto left = have_one ? std::chrono::milliseconds(0)
                               : std::max(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now), std::chrono::milliseconds(0));
    std::chrono::steady_clock::time_point arrival;
    const size_t n = group->receive(datagram, left, arrival);
    if (n == 0) {
      // Nothing waiting: a frame begun longer than the window ago will not complete.
      reassembler->expire(std::chrono::steady_clock::now());
      if (have_one) {
        if (take_ready_message(frame)) return true;
        continue;
      }
      if (std::chrono::steady_clock::now() >= deadline) return false;
      continue;
    }
    bytes += n;
    arrival_ns = wall_clock_ns();
    std::optional<wire::DatagramReassembler::Message> message;
    try {
      message = reassembler->add(std::span<const unsigned char>(datagram).first(n), arrival);
    } catch (const wire::DecodeError& e) {
      last_error = std::string("bad datagram: ") + e.what();  // counted by the reassembler
      continue;
    }
    if (!message) continue;
    if (message->header.model_id != model_id) {
      if (other_model(message->header.model_id, std::chrono::steady_clock::now()))
        return false;  // the new Model comes next
      continue;
    }
    other_model_since = {};
    last_own_frame = std::chrono::steady_clock::now();
    if (have_one) ++superseded;
    ready_message.assign(message->bytes.begin(), message->bytes.end());  // within its capacity: allocates once
    ready_arrival_ns = arrival_ns;
  }
}

bool Subscriber::State::take_ready_message(Frame& frame) {
  const std::span<const unsigned char> bytes = ready_message;
  arrival_ns = ready_arrival_ns;
  bool ready = false;
  // Anyone on the LAN can send to the group: a message that breaks the protocol is counted,
  // never the end of the stream.
  try {
    const wire::MessageHeader header = wire::decode_header(bytes);
    if (header.type != wire::MessageType::Frame || header.version != wire::kVersion2 || header.payload_bytes != bytes.size() - wire::kHeaderBytes)
      throw wire::DecodeError(std::string("a ") + wire::to_string(header.type) + " message of version " + std::to_string(header.version) +
                              " and " + std::to_string(header.payload_bytes) + " bytes, not a version 2 Frame filling the datagrams");
    const std::span<const unsigned char> payload = bytes.subspan(wire::kHeaderBytes);
    if (!(wire::decode_frame_info(payload, version).flags & wire::kFrameParameters)) throw wire::DecodeError("a Frame without parameters");
    ready = on_frame(payload, frame);
  } catch (const wire::DecodeError& e) {
    reject(std::string("bad multicast frame: ") + e.what());
  } catch (const Error& e) {
    reject(std::string("bad multicast frame: ") + e.what());
  }
  ready_message.clear();
  return ready;
}

bool Subscriber::State::other_model(uint32_t id, std::chrono::steady_clock::time_point now) {
  ++frames_other_model;
  char text[128];
  std::snprintf(text, sizeof text, "a multicast frame of another Model (id %08x, this receiver holds %08x): skipped", id, model_id);
  last_error = text;
  if (other_model_since == std::chrono::steady_clock::time_point{}) other_model_since = now;
  if (now - other_model_since < kModelChangeAfter || now - last_own_frame < kModelChangeAfter) return false;
  ++model_fetches;
  other_model_since = {};
  ready_message.clear();  // of the Model that is going
  last_own_frame = now;  // the next fetch, if it comes to that, a second from now at the soonest
  if (offer) {
    wanted_model_id = id;
    listen_to_offer();
  } else {
    connect();
  }
  return true;
}

void Subscriber::State::reject(const std::string& what) {
  ++messages_rejected;
  last_error = what;
}

void Subscriber::State::on_mesh_info(std::span<const unsigned char> payload) {
  const wire::MeshInfo info = wire::decode_mesh_info(payload, version, {options.max_vertices, options.max_markers});
  mesh.subject = info.subject;
  mesh.encoding = version >= wire::kVersion2 ? static_cast<Encoding>(info.encoding)
                                             : (options.encoding == Encoding::Quantised ? Encoding::Quantised : Encoding::Float);
  mesh.vertex_count = info.vertex_count;
  mesh.indices.clear();
  for (const auto& f : info.faces) mesh.indices.insert(mesh.indices.end(), f.begin(), f.end());
  mesh.dominant_part = info.dominant_part;
  mesh.part_count = info.part_count;
  mesh.marker_names = info.marker_names;
  mesh.marker_triangles.clear();
  for (const auto& t : info.marker_triangles) mesh.marker_triangles.insert(mesh.marker_triangles.end(), t.begin(), t.end());
  mesh.source_rate_hz = info.source_rate_hz;
  has_mesh = true;
  ++meshes_received;
  const size_t v3 = 3 * static_cast<size_t>(mesh.vertex_count);
  positions.assign(v3, 0.0f);
  normals.assign(v3, 0.0f);
  markers.assign(3 * info.marker_names.size(), 0.0f);
  marker_status.assign(info.marker_names.size(), 0);
  evaluator.reset();
  model_payload.clear();  // the Model of this MeshInfo comes after it
  compressed.reset();
  if (mesh.encoding == Encoding::Compressed) {
    try {
      compressed = std::make_unique<wire::CompressedVertexDecoder>(static_cast<int>(mesh.vertex_count), info.compressed_order);
    } catch (const std::invalid_argument& e) {
      throw Error(std::string("MeshInfo: ") + e.what());
    }
  }
}

void Subscriber::State::on_model(std::span<const unsigned char> payload) {
  if (!has_mesh) throw Error("a Model message before MeshInfo");
  EvaluationModel model = wire::decode_model(payload);
  if (model.vertex_count() != static_cast<int>(mesh.vertex_count))
    throw Error("the Model has " + std::to_string(model.vertex_count()) + " vertices, MeshInfo " + std::to_string(mesh.vertex_count));
  for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3)
    model.faces.push_back({static_cast<int>(mesh.indices[i]), static_cast<int>(mesh.indices[i + 1]), static_cast<int>(mesh.indices[i + 2])});
  model_payload.assign(payload.begin(), payload.end());
  parameters.resize(model.part_count(), model.member_count());
  parameter_block.reserve(wire::parameter_block_bytes(model.part_count(), model.member_count()));
  // Made only for what evaluates (0.1 s of CPU for the demo body): a load generator that reads
  // headers alone must not spend it, 60 of them joining at once on the daemon's machine.
  if (!options.decode || !options.evaluate) return;
  try {
    evaluator = std::make_unique<MeshEvaluator>(model);
  } catch (const std::invalid_argument& e) {
    throw Error(std::string("the Model does not evaluate: ") + e.what());
  }
}

void Subscriber::State::on_status(std::span<const unsigned char> payload) {
  const wire::Status in = wire::decode_status(payload, version);
  status.state = static_cast<SourceStatus::State>(in.state);
  status.source_rate_hz = in.source_rate_hz;
  status.frames_received = in.frames_received;
  status.frames_published = in.frames_published;
  status.detail = in.detail;
  status.subject = in.subject;
  status.subject_present = in.subject_present;
  if (in.state == wire::SourceStateCode::Refused) throw Error("the daemon refused this subscriber: " + printable_text(in.detail));
}

bool Subscriber::State::on_frame(std::span<const unsigned char> payload, Frame& frame) {
  if (!has_mesh) throw Error("a Frame before MeshInfo");
  const wire::FrameView view = wire::view_frame(payload, version);
  const wire::FrameInfo& info = view.info;
  const size_t v3 = 3 * static_cast<size_t>(mesh.vertex_count);
  bool have_positions = false, have_normals = false;
  if (!options.decode) {
    // The header, markers and times below only.
  } else if (info.flags & wire::kFrameParameters) {
    if (model_payload.empty()) throw Error("a parameter Frame before the Model");
    wire::decode_parameter_block(view.positions, parameters);
    parameter_block.assign(view.positions.begin(), view.positions.end());
    if (options.evaluate) {
      const bool want_normals = options.normals;
      if (!evaluator->evaluate(parameters, positions, want_normals ? std::span<float>(normals) : std::span<float>()))
        throw Error("parameters do not fit the Model");
      have_positions = true;
      have_normals = want_normals;
    }
  } else if (info.flags & wire::kFrameCompressed) {
    if (!compressed || info.vertex_count != mesh.vertex_count) throw Error("a compressed Frame that does not fit MeshInfo");
    const bool with_normals = !view.normals.empty();
    const auto result = compressed->decode(view.positions, view.normals, (info.flags & wire::kFrameKey) != 0, positions,
                                           with_normals ? std::span<float>(normals) : std::span<float>());
    if (result == wire::CompressedVertexDecoder::Result::NeedsKey) {
      ++skipped;
      return false;
    }
    have_positions = true;
    have_normals = with_normals;
  } else if (!(info.flags & wire::kFrameNoPositions)) {
    if (info.vertex_count != mesh.vertex_count) throw Error("a Frame of " + std::to_string(info.vertex_count) + " vertices, MeshInfo says " +
                                                            std::to_string(mesh.vertex_count));
    if (info.flags & wire::kFrameQuantised) {
      float origin[3], step[3];
      std::memcpy(origin, view.positions.data(), 12);
      std::memcpy(step, view.positions.data() + 12, 12);
      const unsigned char* q = view.positions.data() + 24;
      for (size_t i = 0; i < v3; ++i) {
        uint16_t value;
        std::memcpy(&value, q + 2 * i, 2);
        positions[i] = origin[i % 3] + value * step[i % 3];
      }
      for (size_t i = 0; !view.normals.empty() && i < v3; ++i) {
        int16_t value;
        std::memcpy(&value, view.normals.data() + 2 * i, 2);
        normals[i] = value / 32767.0f;
      }
    } else {
      copy_bytes(positions.data(), view.positions.data(), 4 * v3);
      if (!view.normals.empty()) copy_bytes(normals.data(), view.normals.data(), 4 * v3);
    }
    have_positions = true;
    have_normals = !view.normals.empty();
  }
  const size_t m = view.marker_status.size();
  if (m > marker_status.size()) throw Error("a Frame with more markers than MeshInfo names");
  // Nothing that is not finite reaches the renderer (the parameters were checked as they were read).
  if (have_positions && !all_finite(positions)) throw wire::DecodeError("a Frame whose vertices are not all finite");
  if (have_normals && !all_finite(normals)) throw wire::DecodeError("a Frame whose normals are not all finite");
  copy_bytes(markers.data(), view.markers.data(), 12 * m);
  copy_bytes(marker_status.data(), view.marker_status.data(), m);
  if (!all_finite(std::span<const float>(markers).first(3 * m))) throw wire::DecodeError("a Frame whose markers are not all finite");

  frame.frame_number = info.frame_number;
  frame.source_time_ns = info.source_time_ns;
  frame.receive_time_ns = info.receive_time_ns;
  frame.publish_time_ns = info.publish_time_ns;
  frame.arrival_time_ns = arrival_ns;
  const wire::FrameTimecode& t = info.timecode;
  frame.timecode = {(info.flags & wire::kFrameTimecode) != 0, t.hours, t.minutes, t.seconds, t.frames, t.subframe,
                    t.subframes_per_frame, t.rate_hz, (t.flags & wire::kTimecodeDropFrame) != 0};
  frame.markers_filled = info.markers_filled;
  frame.markers_relabelled = info.markers_relabelled;
  frame.pipeline_dropped = info.pipeline_dropped;
  frame.subscriber_dropped = info.subscriber_dropped;
  frame.message_bytes = wire::kHeaderBytes + payload.size();
  frame.key_frame = (info.flags & wire::kFrameKey) != 0;
  frame.positions = have_positions ? std::span<const float>(positions) : std::span<const float>();
  frame.normals = have_normals ? std::span<const float>(normals) : std::span<const float>();
  frame.markers = std::span<const float>(markers).first(3 * m);
  frame.marker_status = std::span<const uint8_t>(marker_status).first(m);
  frame.ready_time_ns = wall_clock_ns();
  return true;
}

bool Subscriber::has_mesh() const { return state_->has_mesh; }
const Mesh& Subscriber::mesh() const { return state_->mesh; }
const SourceStatus& Subscriber::status() const { return state_->status; }
const Options& Subscriber::options() const { return state_->options; }
uint64_t Subscriber::frames_skipped() const { return state_->skipped; }
uint64_t Subscriber::meshes_received() const { return state_->meshes_received; }
uint64_t Subscriber::frames_rejected() const { return state_->rejected; }
std::string Subscriber::last_rejection() const { return state_->last_rejection; }
uint64_t Subscriber::bytes_received() const { return state_->bytes; }
size_t Subscriber::model_bytes() const { return state_->model_payload.empty() ? 0 : wire::kHeaderBytes + state_->model_payload.size(); }
std::span<const unsigned char> Subscriber::parameter_block() const { return state_->parameter_block; }
std::span<const unsigned char> Subscriber::model_payload() const { return state_->model_payload; }

MulticastStats Subscriber::multicast_stats() const {
  const State& s = *state_;
  if (!s.reassembler) return {};
  const wire::DatagramReassembler::Stats& r = s.reassembler->stats();
  return {r.datagrams,
          r.frames_completed,
          r.frames_lost,
          r.frames_incomplete,
          r.datagrams_rejected,
          r.datagrams_other_stream,
          r.datagrams_late,
          r.datagrams_duplicate,
          s.superseded,
          s.messages_rejected,
          s.last_error,
          r.datagrams_out_of_window,
          r.datagrams_unauthenticated,
          r.resyncs,
          s.frames_other_model,
          s.model_fetches,
          s.offer ? s.offer->stats().datagrams : 0,
          s.offers_taken,
          s.offers_rejected,
          s.offer_timeouts};
}

}  // namespace skinstream::client
