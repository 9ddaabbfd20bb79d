// tetcut serve: one live session, simulated on a thread of its own, streamed over WebSocket to
// every page that watches it (Boost.Beast on one Asio thread).
//
// Threads. The simulation thread owns the Session: it runs the commands pages sent (queued under
// a mutex), advances one step per dt of wall time, encodes the frame (and the topology after a
// cut) and posts them to the network thread. The network thread owns every connection; each page
// has a slot for the latest topology and the latest frame, so a slow page skips frames instead of
// queueing them (memory stays bounded however slow it is), and always gets a topology before the
// frames that need it.

#include <tetcut/error.hpp>
#include <tetcut/live_server.hpp>
#include <tetcut/session.hpp>

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <deque>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <thread>

#include "render/viewer_assets.hpp"
#include "server/live_protocol.hpp"
#include "util/stopwatch.hpp"

namespace tetcut {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using Json = nlohmann::json;
using Message = std::shared_ptr<const std::string>;


// A page's pending text messages beyond this are dropped (oldest first): a page that does not
// read cannot grow the server's memory.
constexpr std::size_t kMaxQueuedTexts = 64;
// Frames larger than this close the connection (Beast's own limit; pages' messages above
// kMaxClientMessage but below it get an error reply instead).
constexpr std::size_t kMaxWebSocketMessage = 1 << 20;
constexpr double kStatsSeconds = 0.25;

std::string random_token() {
  std::random_device device;
  std::string token;
  constexpr char kHex[] = "0123456789abcdef";
  for (int i = 0; i < 4; ++i) {
    const std::uint32_t bits = device();
    for (int k = 0; k < 8; ++k) token += kHex[(bits >> (4 * k)) & 15];
  }
  return token;
}

// Equal without an early exit, so the time a refusal takes says nothing about the token.
bool same_token(std::string_view a, std::string_view b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

// The path and the token of a target such as /api/state?token=abc&x=1.
std::pair<std::string_view, std::string_view> path_and_token(std::string_view target) {
  const std::size_t question = target.find('?');
  const std::string_view path = target.substr(0, question);
  std::string_view token;
  if (question != std::string_view::npos) {
    std::string_view query = target.substr(question + 1);
    while (!query.empty()) {
      const std::size_t amp = query.find('&');
      const std::string_view pair = query.substr(0, amp);
      if (pair.substr(0, 6) == "token=") token = pair.substr(6);
      if (amp == std::string_view::npos) break;
      query.remove_prefix(amp + 1);
    }
  }
  return {path, token};
}

bool loopback(const std::string& host) { return host == "127.0.0.1" || host == "localhost" || host == "::1"; }

}  // namespace

namespace live {
// A topology as the pages are sent it: whole, and as the change from the version before (null
// when there is none). In a named namespace: the server's Impl holds it, and a member whose type
// has internal linkage is an error in a unity build.
struct ServedTopology {
  std::uint32_t version = 0;
  std::shared_ptr<const std::string> full, change;
};
}  // namespace live
using TopologyPtr = std::shared_ptr<const live::ServedTopology>;

struct LiveServer::Impl {
  class Page;
  class HttpConnection;

  // The io_context first: it is destroyed last, after everything that uses it.
  asio::io_context io{1};
  tcp::acceptor acceptor{io};
  Scene scene;
  LiveServerOptions options;
  std::string token;
  std::uint16_t bound_port = 0;

  // Network thread only.
  std::map<std::uint64_t, std::weak_ptr<Page>> pages;
  std::uint64_t next_page = 0;
  TopologyPtr latest_topology;
  Message latest_frame;

  // The simulation thread's; read by stop() after it has ended.
  std::optional<Session> session;
  std::uint32_t topology_version = 0;
  live::TopologyEncoder topology_encoder;
  live::NodePieces pieces;
  bool paused = false;
  std::optional<Clock::time_point> blade_received;  // the first blade pose since the last frame
  // Blade poses since the last topology that changed the mesh: each page is told which topology
  // shows its cut (the "cut" reply), so that it can time how soon the cut is seen.
  std::vector<std::pair<std::weak_ptr<Page>, std::int64_t>> cut_causes;

  // Shared, under `mutex`.
  mutable std::mutex mutex;
  std::condition_variable wake;
  std::deque<std::function<void()>> commands;  // run on the simulation thread before its next step
  std::string state;                           // the latest /api/state JSON
  bool stopping = false;

  std::mutex log_mutex;
  std::thread simulation_thread, network_thread;
  std::once_flag stop_once;
  std::atomic<int> connected{0};

  // Figures for the state: rolling means over the steps since the last stats message.
  struct Figures {
    double step_ms = 0, cut_ms = 0, surface_ms = 0, remesh_ms = 0, topology_ms = 0, latency_ms = 0, residual = 0;
    double steps_per_second = 0;
    std::size_t topology_bytes = 0;  // the last topology change's size (the whole one's, when there was no change)
  } figures;

  Impl(Scene s, LiveServerOptions o) : scene(std::move(s)), options(std::move(o)) {
    token = options.token.empty() ? random_token() : options.token;
    boost::system::error_code ec;
    const asio::ip::address address = asio::ip::make_address(options.host == "localhost" ? "127.0.0.1" : options.host, ec);
    if (ec) throw Error(ErrorKind::kInvalidArgument, "not an IP address: '" + options.host + "'");
    const tcp::endpoint endpoint(address, options.port);
    acceptor.open(endpoint.protocol(), ec);
    if (!ec) acceptor.set_option(asio::socket_base::reuse_address(true), ec);
    if (!ec) acceptor.bind(endpoint, ec);
    if (!ec) acceptor.listen(asio::socket_base::max_listen_connections, ec);
    if (ec) throw Error(ErrorKind::kIo, "cannot listen on " + options.host + ":" + std::to_string(options.port) + ": " + ec.message());
    bound_port = acceptor.local_endpoint().port();
    session.emplace(scene);
    publish_topology_and_frame();
  }

  void log(const std::string& line) {
    std::lock_guard lock(log_mutex);
    if (options.log) {
      options.log(line);
    } else {
      std::cerr << "tetcut serve: " << line << std::endl;
    }
  }

  // --- requests -------------------------------------------------------------------------------
  // Whether a request's Host names this server (a page of another site reaching 127.0.0.1 through
  // a rebound DNS name sends its own host name).
  bool host_allowed(std::string_view host) const {
    if (!loopback(options.host)) return true;  // served to other machines on purpose
    const std::string port = ":" + std::to_string(bound_port);
    for (const char* name : {"127.0.0.1", "localhost", "[::1]"}) {
      if (host == std::string(name) + port) return true;
    }
    return false;
  }

  // --- the simulation thread ------------------------------------------------------------------
  void submit(std::function<void()> command) {
    {
      std::lock_guard lock(mutex);
      if (stopping) return;
      commands.push_back(std::move(command));
    }
    wake.notify_one();
  }

  // Sends text to one page (on the network thread).
  void reply(const std::weak_ptr<Page>& page, std::string text);
  void broadcast_text(std::string text);

  void publish_topology_and_frame() {
    live::TopologyEncoder::Messages messages = topology_encoder.encode(++topology_version, *session, &pieces);
    auto topology = std::make_shared<live::ServedTopology>();
    topology->version = messages.version;
    topology->full = std::make_shared<const std::string>(std::move(messages.full));
    if (!messages.change.empty()) topology->change = std::make_shared<const std::string>(std::move(messages.change));
    figures.topology_bytes = (topology->change ? topology->change : topology->full)->size();
    // /api/state tells the new pieces before any page can see them (not after the next step).
    refresh_state();
    publish(std::move(topology));
  }

  // After a cut: the new topology (and a frame) to the pages, timed.
  void publish_cut() {
    const auto start = Clock::now();
    publish_topology_and_frame();
    figures.topology_ms = ms_since(start);
    // From the blade pose reaching the server to the new surface leaving for the pages.
    if (blade_received) figures.latency_ms = ms_since(*blade_received);
    blade_received.reset();
  }

  void publish(TopologyPtr topology) {
    auto frame = std::make_shared<const std::string>(
        live::encode_frame(topology_version, static_cast<std::uint32_t>(session->steps()), session->time(), session->simulator().positions(), pieces));
    asio::post(io, [this, topology = std::move(topology), frame = std::move(frame)] { deliver(topology, frame); });
  }

  void deliver(const TopologyPtr& topology, const Message& frame);

  std::string state_now() {
    Session& s = *session;
    const Json figures_now = {
        {"type", "stats"},
        {"pieces", pieces.count},
        {"tets", s.simulator().num_tets()},
        {"nodes", s.simulator().num_nodes()},
        {"surface_triangles", s.surface().surface.num_triangles()},
        {"time", s.time()},
        {"steps", s.steps()},
        {"cuts", s.cuts_applied()},
        {"hooks", s.num_hooks()},
        {"paused", paused},
        {"pages", connected.load()},
        {"steps_per_second", figures.steps_per_second},
        {"step_ms", figures.step_ms},
        {"cut_ms", figures.cut_ms},
        {"surface_ms", figures.surface_ms},
        {"remesh_ms", figures.remesh_ms},
        {"topology_ms", figures.topology_ms},
        {"topology_bytes", figures.topology_bytes},
        {"cut_latency_ms", figures.latency_ms},
        {"residual", figures.residual},
        {"dt", scene.step.dt},
    };
    return figures_now.dump();
  }

  // The state that GET /api/state answers with, brought up to date; returned for the pages.
  std::string refresh_state() {
    std::string text = state_now();
    std::lock_guard lock(mutex);
    state = text;
    return text;
  }

  void simulate() {
    Clock::time_point next = Clock::now(), window_start = next;
    int window_steps = 0;
    double window_step_ms = 0;
    const auto dt = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(scene.step.dt));
    for (;;) {
      std::deque<std::function<void()>> batch;
      {
        std::unique_lock lock(mutex);
        // Commands are run as they come (a cut is seen without waiting for the tick); steps
        // keep to the clock.
        if (paused) {
          wake.wait_for(lock, std::chrono::milliseconds(50), [&] { return stopping || !commands.empty(); });
        } else if (options.real_time) {
          wake.wait_until(lock, next, [&] { return stopping || !commands.empty(); });
        }
        if (stopping) return;
        batch.swap(commands);
      }
      const bool due = !paused && (!options.real_time || Clock::now() >= next);
      const int changes_before = session->topology_changes();
      const std::uint32_t version_before = topology_version;
      for (auto& command : batch) command();
      bool topology = session->topology_changes() != changes_before && topology_version == version_before;
      const bool changed = !batch.empty();
      // A cut goes out before the step: it is seen a step sooner. Its "cut" replies go first, so
      // that a page knows the topology's cause when the topology comes.
      if (topology) {
        for (const auto& [page, seq] : cut_causes) {
          reply(page, Json{{"type", "cut"}, {"seq", seq}, {"version", topology_version + 1}}.dump());
        }
        publish_cut();
      }
      cut_causes.clear();
      if (due) {
        try {
          const SessionStep step = session->advance();
          if (step.topology_changed && !topology) publish_cut();  // the scene's own timed cuts
          topology = topology || step.topology_changed;
          window_step_ms += step.seconds.step * 1e3;
          ++window_steps;
          figures.residual = step.report.residual;
          if (step.seconds.cut > 0) {
            figures.cut_ms = step.seconds.cut * 1e3;
            figures.surface_ms = step.seconds.surface * 1e3;
            figures.remesh_ms = step.seconds.remesh * 1e3;
          }
        } catch (const std::exception& e) {
          paused = true;
          log(std::string("the simulation stopped: ") + e.what());
          broadcast_text(live::error_message(std::string("the simulation stopped (reset to go on): ") + e.what(), std::nullopt));
        }
      }
      // A frame for each step, and for commands while paused (a pin, a reset); a cut sent its own.
      if (due || (paused && changed && !topology)) publish(nullptr);
      blade_received.reset();
      const double window = seconds_since(window_start);
      if (window >= kStatsSeconds || topology || changed) {
        if (window >= kStatsSeconds) {
          figures.steps_per_second = window_steps / window;
          figures.step_ms = window_steps > 0 ? window_step_ms / window_steps : 0;
          window_start = Clock::now();
          window_steps = 0;
          window_step_ms = 0;
        }
        std::string text = refresh_state();
        if (window >= kStatsSeconds) broadcast_text(std::move(text));
      }
      if (due) next += dt;
      // Fallen behind (a slow step, a reset): start again from now rather than race to catch up.
      if (Clock::now() - next > std::chrono::milliseconds(250) || paused) next = Clock::now();
    }
  }

  // Runs a page's command on the simulation thread; errors go back to that page only.
  void command(const std::weak_ptr<Page>& page, live::ClientCommand command, Clock::time_point received);

  void write_recording_file() {
    if (options.record.empty() || !session) return;
    try {
      write_recording(options.record, scene, *session);
      log("wrote the recording to " + options.record.string());
    } catch (const std::exception& e) {
      log(std::string("could not write the recording: ") + e.what());
    }
  }

  void accept();
  void shut_down_network();
  // Accepting connections (on the network thread, once it runs) and simulating (on its own).
  void begin() {
    accept();
    simulation_thread = std::thread([this] { simulate(); });
  }
};

// --- a page's WebSocket ------------------------------------------------------------------------
class LiveServer::Impl::Page : public std::enable_shared_from_this<Page> {
 public:
  Page(Impl& server, tcp::socket socket, std::uint64_t id) : server_(server), ws_(std::move(socket)), id_(id) {}

  void start(http::request<http::string_body> request) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& response) {
      response.set(http::field::server, "tetcut");
    }));
    ws_.read_message_max(kMaxWebSocketMessage);
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return self->server_.log("a WebSocket handshake failed: " + ec.message());
      self->server_.pages[self->id_] = self;
      ++self->server_.connected;
      self->server_.log("page " + std::to_string(self->id_) + " joined");
      self->offer(self->server_.latest_topology, self->server_.latest_frame);
      self->read();
    });
  }

  // The newest topology (when there is one) and frame; frames not yet sent are dropped. A
  // topology goes as its change from the version the page will have, while the changes queued
  // for it weigh less than the whole (then the whole replaces them): the page applies them in
  // order, and however slow it is, at most a whole topology's bytes wait for it.
  void offer(const TopologyPtr& topology, const Message& frame) {
    if (topology) {
      const Message& change = topology->change;
      if (change && version_ + 1 == topology->version && topology_bytes_ + change->size() <= topology->full->size()) {
        topologies_.push_back(change);
        topology_bytes_ += change->size();
      } else {
        topologies_.assign(1, topology->full);
        topology_bytes_ = topology->full->size();
      }
      version_ = topology->version;
    }
    if (frame) frame_ = frame;
    write();
  }
  void text(std::string message) {
    if (texts_.size() >= kMaxQueuedTexts) texts_.pop_front();
    texts_.push_back(std::make_shared<const std::string>(std::move(message)));
    write();
  }
  void close() {
    if (closed_) return;
    closed_ = true;
    ws_.async_close(websocket::close_code::going_away, [self = shared_from_this()](beast::error_code) {});
  }

 private:
  void read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

  void on_read(beast::error_code ec) {
    if (ec) {
      if (ec != websocket::error::closed && ec != asio::error::operation_aborted) {
        server_.log("page " + std::to_string(id_) + ": " + ec.message());
      }
      return leave();
    }
    const std::string message = beast::buffers_to_string(buffer_.data());
    buffer_.consume(buffer_.size());
    const bool binary = !ws_.got_text();
    std::optional<std::int64_t> seq;
    try {
      if (binary) throw Error(ErrorKind::kInvalidArgument, "binary messages are not accepted: send JSON text");
      live::ClientCommand command = live::parse_client_message(message);
      seq = command.seq;
      if (command.seq) {
        if (last_seq_ && *command.seq <= *last_seq_) {
          throw Error(ErrorKind::kInvalidArgument,
                      "out of order: seq " + std::to_string(*command.seq) + " after " + std::to_string(*last_seq_));
        }
        last_seq_ = command.seq;
      }
      server_.command(weak_from_this(), std::move(command), Clock::now());
    } catch (const Error& e) {
      if (e.kind() == ErrorKind::kInternal) throw;  // a bug, not a message to refuse
      server_.log("page " + std::to_string(id_) + ": refused a message (" + std::to_string(message.size()) + " bytes): " + e.what());
      text(live::error_message(e.what(), seq));
    }
    read();
  }

  void write() {
    if (writing_ || closed_) return;
    Message next;
    bool binary = true;
    if (!texts_.empty()) {
      next = std::move(texts_.front());
      texts_.pop_front();
      binary = false;
    } else if (!topologies_.empty()) {
      next = std::move(topologies_.front());
      topologies_.pop_front();
      topology_bytes_ -= next->size();
    } else if (frame_) {
      next = std::move(frame_);
      frame_.reset();
    } else {
      return;
    }
    writing_ = true;
    ws_.binary(binary);
    ws_.async_write(asio::buffer(*next), [self = shared_from_this(), next](beast::error_code ec, std::size_t) {
      self->writing_ = false;
      if (ec) return self->leave();
      self->write();
    });
  }

  void leave() {
    if (server_.pages.erase(id_) > 0) {
      --server_.connected;
      server_.log("page " + std::to_string(id_) + " left");
    }
    closed_ = true;
  }

  Impl& server_;
  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer buffer_;
  std::uint64_t id_;
  std::deque<Message> texts_;
  std::deque<Message> topologies_;  // to send, in order
  std::size_t topology_bytes_ = 0;  // their size
  std::uint32_t version_ = 0;       // the topology version the page has once they are sent
  Message frame_;
  std::optional<std::int64_t> last_seq_;
  bool writing_ = false, closed_ = false;
};

void LiveServer::Impl::reply(const std::weak_ptr<Page>& page, std::string text) {
  asio::post(io, [page, text = std::move(text)]() mutable {
    if (const auto p = page.lock()) p->text(std::move(text));
  });
}

void LiveServer::Impl::broadcast_text(std::string text) {
  asio::post(io, [this, text = std::move(text)] {
    for (const auto& [id, page] : pages) {
      if (const auto p = page.lock()) p->text(text);
    }
  });
}

void LiveServer::Impl::deliver(const TopologyPtr& topology, const Message& frame) {
  if (topology) latest_topology = topology;
  latest_frame = frame;
  for (const auto& [id, page] : pages) {
    if (const auto p = page.lock()) p->offer(topology, frame);
  }
}

void LiveServer::Impl::command(const std::weak_ptr<Page>& page, live::ClientCommand command, Clock::time_point received) {
  submit([this, page, command = std::move(command), received] {
    try {
      switch (command.kind) {
        case live::ClientCommand::Kind::kPause:
          paused = command.paused;
          return;
        case live::ClientCommand::Kind::kReset: {
          const auto start = Clock::now();
          session.emplace(scene);
          paused = false;
          publish_topology_and_frame();
          broadcast_text(Json{{"type", "reset"}}.dump());
          log("reset the session (" + std::to_string(static_cast<int>(ms_since(start))) + " ms)");
          return;
        }
        case live::ClientCommand::Kind::kEvent:
          break;
      }
      const SessionEvent& e = command.event;
      if (e.kind == SessionEvent::Kind::kGrab) {
        const int hook = session->grab(e.point, e.stiffness);
        Json answer = {{"type", "grabbed"}, {"hook", hook}};
        if (command.seq) answer["seq"] = *command.seq;
        reply(page, answer.dump());
      } else {
        const int changes_before = session->topology_changes();
        session->apply(e);
        if (session->topology_changes() != changes_before) {
          if (!blade_received) blade_received = received;
          if (command.seq) cut_causes.emplace_back(page, *command.seq);
        }
      }
    } catch (const Error& e) {
      if (e.kind() == ErrorKind::kInternal) throw;  // a bug, not an event to refuse
      log(std::string("refused an event: ") + e.what());
      reply(page, live::error_message(e.what(), command.seq));
    }
  });
}

// --- HTTP --------------------------------------------------------------------------------------
class LiveServer::Impl::HttpConnection : public std::enable_shared_from_this<HttpConnection> {
 public:
  HttpConnection(Impl& server, tcp::socket socket) : server_(server), stream_(std::move(socket)) {}
  void start() { read(); }

 private:
  void read() {
    parser_.emplace();
    parser_->body_limit(live::kMaxClientMessage);
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(stream_, buffer_, *parser_, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

  void on_read(beast::error_code ec) {
    if (ec == http::error::end_of_stream || ec == beast::error::timeout) return close();
    if (ec) {
      server_.log("a bad HTTP request: " + ec.message());
      return respond(simple(http::status::bad_request, "bad request: " + ec.message() + "\n"));
    }
    http::request<http::string_body> request = parser_->release();
    const beast::string_view target = request.target();
    const auto [path, token] = path_and_token(std::string_view(target.data(), target.size()));
    const bool token_ok = same_token(token, server_.token);
    const std::string host(request[http::field::host]);
    if (!server_.host_allowed(host)) {
      server_.log("refused a request for host '" + host + "'");
      return respond(simple(http::status::forbidden, "403: this server answers only to its own address\n", request.version()));
    }
    if (websocket::is_upgrade(request)) {
      const std::string origin(request[http::field::origin]);
      if (!token_ok || path != "/live" || (!origin.empty() && origin != "http://" + host)) {
        server_.log("refused a WebSocket upgrade (" + std::string(!token_ok ? "wrong token" : path != "/live" ? "wrong path" : "origin " + origin) + ")");
        return respond(simple(http::status::forbidden, "403: a WebSocket needs the token, from this server's page\n", request.version()));
      }
      stream_.expires_never();
      const auto page = std::make_shared<Page>(server_, stream_.release_socket(), server_.next_page++);
      page->start(std::move(request));
      return;
    }
    if (request.method() != http::verb::get) {
      return respond(simple(http::status::method_not_allowed, "405: only GET\n", request.version()));
    }
    if (!token_ok) {
      server_.log("refused " + std::string(path) + " without the token");
      return respond(simple(http::status::forbidden, "403: open the address tetcut serve printed (with its token)\n", request.version()));
    }
    if (path == "/") {
      if (view::kLiveScript.empty()) {
        return respond(simple(http::status::service_unavailable, "this tetcut was built without the web viewer (Node.js)\n", request.version()));
      }
      const Vec3& g = server_.scene.step.gravity;
      const std::string config = Json{{"gravity", {g[0], g[1], g[2]}}, {"dt", server_.scene.step.dt}}.dump();
      std::string page(view::kLivePage);
      for (const auto& [slot, text] : {std::pair<std::string_view, std::string_view>{"{{CONFIG}}", config}, {"{{SCRIPT}}", view::kLiveScript}}) {
        const std::size_t at = page.find(slot);
        if (at != std::string::npos) page.replace(at, slot.size(), text);
      }
      auto response = simple(http::status::ok, std::move(page), request.version(), "text/html; charset=utf-8");
      // Nothing on the page may reach another machine: scripts and styles are inline, the only
      // connection is this server's WebSocket.
      response->set("Content-Security-Policy",
                    "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src data: blob:; "
                    "connect-src 'self' ws://" + host);
      return respond(std::move(response));
    }
    if (path == "/api/state") {
      std::string state;
      {
        std::lock_guard lock(server_.mutex);
        state = server_.state;
      }
      return respond(simple(http::status::ok, state + "\n", request.version(), "application/json"));
    }
    if (path == "/api/recording") {
      // The session lives on the simulation thread: the recording is written there, sent here.
      const unsigned version = request.version();
      server_.submit([this, self = shared_from_this(), version] {
        std::string text = recording_json(server_.scene, *server_.session);
        asio::post(server_.io, [self, version, text = std::move(text)]() mutable {
          auto response = self->simple(http::status::ok, std::move(text), version, "application/json");
          response->set(http::field::content_disposition, "attachment; filename=\"tetcut-recording.json\"");
          self->respond(std::move(response));
        });
      });
      return;
    }
    respond(simple(http::status::not_found, "404: no such page\n", request.version()));
  }

  std::shared_ptr<http::response<http::string_body>> simple(http::status status, std::string body, unsigned version = 11,
                                                            const char* type = "text/plain; charset=utf-8") {
    auto response = std::make_shared<http::response<http::string_body>>(status, version);
    response->set(http::field::server, "tetcut");
    response->set(http::field::content_type, type);
    response->set(http::field::cache_control, "no-store");
    response->keep_alive(status == http::status::ok);
    response->body() = std::move(body);
    response->prepare_payload();
    return response;
  }

  void respond(std::shared_ptr<http::response<http::string_body>> response) {
    http::async_write(stream_, *response, [self = shared_from_this(), response](beast::error_code ec, std::size_t) {
      if (ec || !response->keep_alive()) return self->close();
      self->read();
    });
  }

  void close() {
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
  }

  Impl& server_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
};

void LiveServer::Impl::accept() {
  acceptor.async_accept(io, [this](beast::error_code ec, tcp::socket socket) {
    if (ec) {
      if (ec != asio::error::operation_aborted) log("accept: " + ec.message());
      if (!acceptor.is_open()) return;
    } else {
      // Small messages (a frame, a "cut" reply) go out at once: with Nagle's algorithm a small
      // write behind a large one waits for the page's delayed ACK (40 ms on Linux).
      beast::error_code nodelay_ec;
      socket.set_option(tcp::no_delay(true), nodelay_ec);
      std::make_shared<HttpConnection>(*this, std::move(socket))->start();
    }
    accept();
  });
}

void LiveServer::Impl::shut_down_network() {
  beast::error_code ec;
  acceptor.close(ec);
  for (const auto& [id, page] : pages) {
    if (const auto p = page.lock()) p->close();
  }
  io.stop();
}

// --- LiveServer ------------------------------------------------------------------------------
LiveServer::LiveServer(Scene scene, LiveServerOptions options) : impl_(std::make_unique<Impl>(std::move(scene), std::move(options))) {
  std::lock_guard lock(impl_->mutex);
  impl_->state = impl_->state_now();
}

LiveServer::~LiveServer() { stop(); }

std::uint16_t LiveServer::port() const { return impl_->bound_port; }
const std::string& LiveServer::token() const { return impl_->token; }
std::string LiveServer::url() const {
  const std::string& host = impl_->options.host;
  const std::string shown = host.find(':') != std::string::npos ? "[" + host + "]" : host == "0.0.0.0" ? "127.0.0.1" : host;
  return "http://" + shown + ":" + std::to_string(port()) + "/?token=" + impl_->token;
}

std::string LiveServer::state_json() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->state;
}

void LiveServer::start() {
  impl_->begin();
  impl_->network_thread = std::thread([this] { impl_->io.run(); });
}

void LiveServer::run() {
  impl_->begin();
  // A log line to a closed terminal or pipe must not kill the session before it is recorded.
  std::signal(SIGPIPE, SIG_IGN);
  // Ctrl-C (or a TERM) ends the session cleanly: stop() writes the recording.
  asio::signal_set signals(impl_->io, SIGINT, SIGTERM);
  signals.async_wait([this](beast::error_code ec, int) {
    if (!ec) impl_->log("stopping");
    if (!ec) impl_->shut_down_network();
  });
  impl_->io.run();
  stop();
}

void LiveServer::stop() {
  std::call_once(impl_->stop_once, [this] {
    {
      std::lock_guard lock(impl_->mutex);
      impl_->stopping = true;
    }
    impl_->wake.notify_all();
    if (impl_->simulation_thread.joinable()) impl_->simulation_thread.join();
    asio::post(impl_->io, [this] { impl_->shut_down_network(); });
    if (impl_->network_thread.joinable()) impl_->network_thread.join();
    impl_->write_recording_file();
  });
}

}  // namespace tetcut
