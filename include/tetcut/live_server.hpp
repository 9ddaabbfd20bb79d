#pragma once
// The live session over the network: `tetcut serve`. An HTTP and WebSocket server (Boost.Beast)
// that runs one tetcut::Session on a thread of its own at a fixed dt, paced to real time, and
// streams it to every page that connects; pages send blade poses, hooks and pins back.
//
//   tetcut::LiveServer server(tetcut::load_scene("scene.json"), {});  // binds 127.0.0.1, a free port
//   std::cout << server.url() << "\n";    // http://127.0.0.1:PORT/?token=...
//   server.run();                          // until stop() (another thread, or a signal handler)
//
// Every request needs the token (403 without it); WebSocket upgrades also need an Origin of the
// server itself (or none, as a non-browser client sends), and a Host naming it (so a page of
// another site cannot reach it through DNS rebinding). Pages' messages are size-limited and
// checked; a bad one gets an error reply and is logged, and nothing else changes. The wire format
// is described in src/server/live_protocol.hpp.
//
// Routes: GET /?token=T (the page), /api/state?token=T (JSON: pieces, tets, nodes, surface
// triangles, simulated time, steps per second, step and cut milliseconds), /api/recording?token=T
// (the session's events as a scene file that `tetcut sim` replays), and the WebSocket /live?token=T.

#include <tetcut/scene.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

namespace tetcut {

struct LiveServerOptions {
  /// The address to bind: 127.0.0.1 unless another is asked for.
  std::string host = "127.0.0.1";
  /// 0: a free port, chosen by the system (port() says which).
  std::uint16_t port = 0;
  /// Empty: 128 random bits, in hex.
  std::string token;
  /// Where stop() writes the session's recording; empty: nowhere.
  std::filesystem::path record;
  /// Where log lines go (connections, refused messages); default: standard error.
  std::function<void(const std::string&)> log;
  /// Steps are paced to real time (one per dt); off, they run as fast as they can (benchmarks).
  bool real_time = true;
};

class LiveServer {
 public:
  /// Builds the session (the scene's mesh, or its surface embedded) and binds. Throws Error(kIo)
  /// when the address cannot be bound, Error(kInvalidArgument) for a malformed host.
  LiveServer(Scene scene, LiveServerOptions options);
  ~LiveServer();  ///< stop()
  LiveServer(const LiveServer&) = delete;
  LiveServer& operator=(const LiveServer&) = delete;

  std::uint16_t port() const;
  const std::string& token() const;
  /// http://HOST:PORT/?token=TOKEN
  std::string url() const;

  /// Serves on this thread (and simulates on another) until stop().
  void run();
  /// Serves on threads of its own; returns at once.
  void start();
  /// Stops serving and simulating, closes every connection and writes the recording (when
  /// options.record names a file). Safe from any thread, and more than once.
  void stop();

  /// GET /api/state's JSON.
  std::string state_json() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tetcut
