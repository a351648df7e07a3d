#pragma once
// Capture-system servers that go silent, for the handshake and stall tests of the QTM RT, NatNet
// and Vicon DataStream sources (in-process and through the real daemon): each serves every
// connection its protocol's handshake and then `frames` frames, and then says nothing more while
// the connection stays open (TCP) or while it keeps receiving (NatNet). With `handshake` false it
// says nothing at all: a server that accepts and never answers. connections() counts the
// connections (NatNet: CONNECT requests), so a test sees the client leave and come back.
#include <array>
#include <atomic>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "protocol/natnet/natnet.h"
#include "protocol/natnet/natnet_writer.h"
#include "protocol/qtm/qtm_packet_framer.h"
#include "protocol/qtm/qtm_packet_reader.h"
#include "protocol/qtm/qtm_packet_writer.h"
#include "protocol/qtm/qtm_parameters.h"
#include "protocol/qtm/qtm_rt.h"
#include "protocol/vicon/vicon_packet_writer.h"
#include "server/asio.h"

namespace skinstream::test {

struct SilenceOptions {
  bool handshake = true;  // false: not a word, from the start
  int frames = 5;         // after the handshake, then silence
};

// The TCP servers' common part: one connection at a time, each served by `serve` on this
// server's thread until the client leaves.
class SilentTcpServer {
 public:
  ~SilentTcpServer() {
    done_ = true;
    boost::system::error_code ec;
    {
      // A connection being served ends when its socket is shut down under it (a close would not
      // wake the blocked read) ...
      std::lock_guard lock(mutex_);
      if (current_) current_->shutdown(server::tcp::socket::shutdown_both, ec);
    }
    // ... and a waiting accept() when someone connects.
    server::tcp::socket poke(io_);
    poke.connect(server::tcp::endpoint(server::asio::ip::make_address("127.0.0.1"), port_), ec);
    if (thread_.joinable()) thread_.join();
  }
  uint16_t port() const { return port_; }
  int connections() const { return connections_.load(); }

 protected:
  using Serve = std::function<void(server::tcp::socket&)>;
  void start(Serve serve) {
    acceptor_.open(server::tcp::v4());
    acceptor_.bind(server::tcp::endpoint(server::asio::ip::make_address("127.0.0.1"), 0));
    acceptor_.listen();
    port_ = acceptor_.local_endpoint().port();
    thread_ = std::thread([this, serve] {
      while (!done_) {
        server::tcp::socket socket(io_);
        boost::system::error_code ec;
        acceptor_.accept(socket, ec);
        if (ec || done_) return;
        ++connections_;
        {
          std::lock_guard lock(mutex_);
          current_ = &socket;
        }
        try {
          serve(socket);
        } catch (const std::exception&) {  // the client went away
        }
        std::lock_guard lock(mutex_);
        current_ = nullptr;
      }
    });
  }
  // Reads until the client closes the connection: the server's silence, with the socket open.
  static void hold(server::tcp::socket& socket) {
    std::array<unsigned char, 4096> sink;
    for (;;) socket.read_some(server::asio::buffer(sink));
  }

 private:
  server::asio::io_context io_;
  server::tcp::acceptor acceptor_{io_};
  uint16_t port_ = 0;
  std::atomic<int> connections_{0};
  std::atomic<bool> done_{false};
  std::mutex mutex_;
  server::tcp::socket* current_ = nullptr;
  std::thread thread_;
};

// QTM RT: the welcome, the answers to Version and GetParameters (one label, "P_A", at 120 Hz),
// and after StreamFrames `frames` Data packets.
class SilentQtmServer : public SilentTcpServer {
 public:
  explicit SilentQtmServer(SilenceOptions options) {
    start([options](server::tcp::socket& s) {
      if (!options.handshake) hold(s);
      qtm::PacketFramer framer;
      auto next_command = [&] {
        for (;;) {
          qtm::Bytes packet;
          if (framer.next(packet) == qtm::PacketFramer::Status::Packet) return;
          const auto room = framer.prepare(4096);
          framer.commit(s.read_some(server::asio::buffer(room.data(), room.size())));
        }
      };
      auto send = [&](std::span<const unsigned char> bytes) { server::asio::write(s, server::asio::buffer(bytes.data(), bytes.size())); };
      send(qtm::encode_text(qtm::PacketType::Command, qtm::kWelcome));
      next_command();
      send(qtm::encode_text(qtm::PacketType::Command, "Version set to 1." + std::to_string(qtm::kSpokenMinorVersion)));
      next_command();
      qtm::Parameters parameters;
      parameters.frequency_hz = 120;
      parameters.has_3d = true;
      parameters.labels = {"P_A"};
      send(qtm::encode_text(qtm::PacketType::Xml, qtm::write_parameters_xml(parameters, qtm::kSpokenMinorVersion)));
      next_command();  // StreamFrames
      qtm::DataPacketWriter writer;
      const std::array<std::array<float, 3>, 1> position = {{{100.0f, 200.0f, 1000.0f}}};
      for (int k = 0; k < options.frames; ++k) {
        writer.begin(k * 8333, static_cast<uint32_t>(k + 1));
        writer.add_labelled(position);
        send(writer.finish());
      }
      hold(s);
    });
  }
};

// Vicon DataStream: ObjectEnums, then after the client's request `frames` packets of StreamInfo
// (120 Hz) and FrameInfo.
class SilentViconServer : public SilentTcpServer {
 public:
  explicit SilentViconServer(SilenceOptions options) {
    start([options](server::tcp::socket& s) {
      if (!options.handshake) hold(s);
      namespace type = vicon::object_type;
      server::asio::write(s, server::asio::buffer(vicon::encode_packet(vicon::ObjectEnums{{type::StreamInfo, type::FrameInfo}})));
      std::array<unsigned char, 4096> request;
      s.read_some(server::asio::buffer(request));  // the client's choice and RequestFrame
      for (int k = 0; k < options.frames; ++k)
        server::asio::write(s, server::asio::buffer(vicon::encode_packet(vicon::StreamInfo{1'125'000}, vicon::FrameInfo{static_cast<uint32_t>(k)})));
      hold(s);
    });
  }
};

// NatNet 4.1, unicast: SERVERINFO to CONNECT, then to REQUEST_MODELDEF one marker set ("P", one
// marker "A") and `frames` frames; KEEPALIVEs unanswered.
class SilentNatNetServer {
 public:
  explicit SilentNatNetServer(SilenceOptions options)
      : socket_(io_, server::udp::endpoint(server::asio::ip::make_address("127.0.0.1"), 0)), thread_([this, options] {
          std::vector<unsigned char> buffer(natnet::kMaxMessageBytes);
          for (;;) {
            server::udp::endpoint client;
            boost::system::error_code ec;
            const size_t n = socket_.receive_from(server::asio::buffer(buffer), client, 0, ec);
            if (ec || done_) return;
            if (n < natnet::kHeaderBytes) continue;
            const uint16_t request = static_cast<uint16_t>(buffer[0] | buffer[1] << 8);
            if (request == natnet::message::Connect) ++connections_;
            if (!options.handshake) continue;
            if (request == natnet::message::Connect) {
              natnet::ServerInfo info;
              info.multicast = false;
              socket_.send_to(server::asio::buffer(natnet::encode_server_info(info)), client, 0, ec);
            } else if (request == natnet::message::RequestModelDef) {
              natnet::ModelDefinitions definitions;
              definitions.marker_sets.push_back({"P", {"A"}});
              socket_.send_to(server::asio::buffer(natnet::encode_model_definitions(definitions, {4, 1})), client, 0, ec);
              natnet::FrameOfData frame;
              frame.marker_sets.push_back({"P", {{0.1f, 0.2f, 1.0f}}});
              frame.marker_set_count = 1;
              natnet::ByteVector bytes;
              for (int k = 0; k < options.frames; ++k) {
                frame.frame_number = k + 1;
                frame.timestamp_s = k / 120.0;
                natnet::encode_frame(frame, {4, 1}, bytes);
                socket_.send_to(server::asio::buffer(bytes), client, 0, ec);
              }
            }
          }
        }) {}
  ~SilentNatNetServer() {
    done_ = true;
    boost::system::error_code ec;
    server::udp::socket poke(io_, server::udp::v4());
    poke.send_to(server::asio::buffer("x", 1), socket_.local_endpoint(), 0, ec);  // wakes receive_from()
    thread_.join();
  }
  uint16_t port() const { return socket_.local_endpoint().port(); }
  int connections() const { return connections_.load(); }

 private:
  server::asio::io_context io_;
  server::udp::socket socket_;
  std::atomic<int> connections_{0};
  std::atomic<bool> done_{false};
  std::thread thread_;
};

}  // namespace skinstream::test
