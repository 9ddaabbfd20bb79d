// The live session's messages: parsing what a page sends (shape and finiteness; the session
// checks the rest) and encoding what it is sent. See live_protocol.hpp for the layout.

#include "server/live_protocol.hpp"

#include <tetcut/error.hpp>
#include <tetcut/render.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "util/union_find.hpp"

namespace tetcut::live {
namespace {

using Json = nlohmann::json;

[[noreturn]] void refuse(const std::string& message) { throw Error(ErrorKind::kInvalidArgument, message); }

Vec3 vec3(const Json& message, const char* key) {
  const auto it = message.find(key);
  if (it == message.end()) refuse(std::string("missing '") + key + "'");
  if (!it->is_array() || it->size() != 3) refuse(std::string("'") + key + "' must be 3 finite numbers");
  Vec3 v;
  for (int c = 0; c < 3; ++c) {
    const Json& x = (*it)[static_cast<std::size_t>(c)];
    if (!x.is_number() || !std::isfinite(x.get<double>())) refuse(std::string("'") + key + "' must be 3 finite numbers");
    v[c] = x.get<double>();
  }
  return v;
}

double number(const Json& message, const char* key, std::optional<double> fallback = std::nullopt) {
  const auto it = message.find(key);
  if (it == message.end()) {
    if (fallback) return *fallback;
    refuse(std::string("missing '") + key + "'");
  }
  if (!it->is_number() || !std::isfinite(it->get<double>())) refuse(std::string("'") + key + "' must be a finite number");
  return it->get<double>();
}

int hook_number(const Json& message) {
  const auto it = message.find("hook");
  if (it == message.end()) refuse("missing 'hook'");
  if (!it->is_number_integer() || it->get<std::int64_t>() < 0 || it->get<std::int64_t>() > 1'000'000'000) {
    refuse("'hook' must be a hook's number");
  }
  return static_cast<int>(it->get<std::int64_t>());
}

// Appends a value's bytes (the formats are little-endian, as every machine this runs on).
template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

void pad4(std::string& out) { out.append((4 - out.size() % 4) % 4, '\0'); }

}  // namespace

ClientCommand parse_client_message(std::string_view text) {
  if (text.size() > kMaxClientMessage) {
    refuse("a message of " + std::to_string(text.size()) + " bytes: the limit is " + std::to_string(kMaxClientMessage));
  }
  Json message = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (message.is_discarded()) refuse("not valid JSON");
  if (!message.is_object()) refuse("a message must be a JSON object");
  ClientCommand command;
  if (const auto seq = message.find("seq"); seq != message.end()) {
    if (!seq->is_number_integer() || seq->get<std::int64_t>() < 0) refuse("'seq' must be a non-negative integer");
    command.seq = seq->get<std::int64_t>();
  }
  const auto type = message.find("type");
  if (type == message.end() || !type->is_string()) refuse("a message needs a 'type'");
  const std::string kind = type->get<std::string>();
  SessionEvent& e = command.event;
  using K = SessionEvent::Kind;
  if (kind == "blade") {
    e.kind = K::kBlade;
    e.pose = {vec3(message, "a"), vec3(message, "b")};
  } else if (kind == "lift") {
    e.kind = K::kLiftBlade;
  } else if (kind == "grab") {
    e.kind = K::kGrab;
    e.point = vec3(message, "point");
    e.stiffness = number(message, "stiffness", 0.0);
    if (e.stiffness < 0) refuse("'stiffness' must not be negative");
  } else if (kind == "move_hook") {
    e.kind = K::kMoveHook;
    e.hook = hook_number(message);
    e.point = vec3(message, "target");
  } else if (kind == "release") {
    e.kind = K::kRelease;
    e.hook = hook_number(message);
  } else if (kind == "pin" || kind == "unpin") {
    e.kind = kind == "pin" ? K::kPin : K::kUnpin;
    e.point = vec3(message, "point");
    e.radius = number(message, "radius");
    if (!(e.radius > 0)) refuse("'radius' must be positive");
  } else if (kind == "pause") {
    command.kind = ClientCommand::Kind::kPause;
    const auto paused = message.find("paused");
    if (paused == message.end() || !paused->is_boolean()) refuse("'paused' must be true or false");
    command.paused = paused->get<bool>();
  } else if (kind == "reset") {
    command.kind = ClientCommand::Kind::kReset;
  } else {
    // The type is echoed escaped (dump), so a page's bytes never reach the log raw.
    refuse("unknown message type " + Json(kind).dump(-1, ' ', true, Json::error_handler_t::replace));
  }
  return command;
}

NodePieces node_pieces(const std::vector<std::array<Index, 4>>& copy_nodes, Index num_nodes) {
  UnionFind classes(static_cast<std::size_t>(num_nodes));
  for (const auto& copy : copy_nodes) {
    for (int k = 1; k < 4; ++k) classes.join(copy[0], copy[k]);
  }
  std::vector<Index> size(static_cast<std::size_t>(num_nodes), 0);
  for (Index n = 0; n < num_nodes; ++n) ++size[classes.find(n)];
  std::vector<Index> roots;
  for (Index n = 0; n < num_nodes; ++n) {
    if (classes.find(n) == n) roots.push_back(n);
  }
  std::stable_sort(roots.begin(), roots.end(), [&](Index a, Index b) { return size[a] > size[b]; });
  std::vector<std::uint32_t> number(static_cast<std::size_t>(num_nodes), 0);
  for (std::size_t i = 0; i < roots.size(); ++i) number[roots[i]] = static_cast<std::uint32_t>(i);
  NodePieces out;
  out.count = static_cast<std::uint32_t>(roots.size());
  out.node_piece.resize(static_cast<std::size_t>(num_nodes));
  for (Index n = 0; n < num_nodes; ++n) out.node_piece[n] = number[classes.find(n)];
  return out;
}

std::string encode_topology(std::uint32_t version, const std::vector<std::array<Index, 4>>& copy_nodes,
                            const NodePieces& pieces, const MaterialSurface& surface) {
  const TriangleSurface& s = surface.surface;
  const auto u32 = [](Index i) { return static_cast<std::uint32_t>(i); };
  const Index num_nodes = static_cast<Index>(pieces.node_piece.size());
  std::string out;
  out.reserve(32 + 16 * copy_nodes.size() + 4 * pieces.node_piece.size() + 24 * static_cast<std::size_t>(s.num_vertices()) +
              12 * static_cast<std::size_t>(s.num_triangles()));
  for (const std::uint32_t v : {kTopologyMessage, version, u32(static_cast<Index>(copy_nodes.size())), u32(num_nodes),
                                u32(s.num_vertices()), u32(s.num_triangles()), pieces.count, 0u}) {
    put(out, v);
  }
  for (const auto& copy : copy_nodes) {
    for (const Index n : copy) put(out, u32(n));
  }
  for (const std::uint32_t p : pieces.node_piece) put(out, p);
  for (Index v = 0; v < s.num_vertices(); ++v) put(out, u32(surface.vertex_tet[v]));
  for (Index v = 0; v < s.num_vertices(); ++v) {
    for (int k = 0; k < 4; ++k) put(out, static_cast<float>(surface.vertex_weights(v, k)));
  }
  for (Index t = 0; t < s.num_triangles(); ++t) {
    for (int k = 0; k < 3; ++k) put(out, u32(s.triangles(t, k)));
  }
  for (Index v = 0; v < s.num_vertices(); ++v) {
    const auto rgb = render::piece_colour(pieces.node_piece[copy_nodes[surface.vertex_tet[v]][0]]);
    out.append(reinterpret_cast<const char*>(rgb.data()), 3);
  }
  pad4(out);
  return out;
}

std::string encode_topology(std::uint32_t version, Session& session, NodePieces* pieces) {
  const Cutter& cutter = session.cutter();
  *pieces = node_pieces(cutter.tet_nodes(), cutter.num_nodes());
  return encode_topology(version, cutter.tet_nodes(), *pieces, session.surface());
}

std::string encode_frame(std::uint32_t version, std::uint32_t step, double time, const Points& nodes, const NodePieces& pieces) {
  const std::size_t count = pieces.count;
  std::string out;
  out.reserve(32 + 24 * count + 6 * static_cast<std::size_t>(nodes.rows()) + 2);
  for (const std::uint32_t v : {kFrameMessage, version, step, static_cast<std::uint32_t>(nodes.rows()), pieces.count, 0u}) put(out, v);
  put(out, time);
  std::vector<Vec3> low(count, Vec3::Constant(std::numeric_limits<double>::infinity()));
  std::vector<Vec3> high(count, Vec3::Constant(-std::numeric_limits<double>::infinity()));
  for (Index n = 0; n < nodes.rows(); ++n) {
    const std::uint32_t p = pieces.node_piece[n];
    low[p] = low[p].cwiseMin(nodes.row(n).transpose());
    high[p] = high[p].cwiseMax(nodes.row(n).transpose());
  }
  // In float, as the page reads them: the quantisation below uses the same rounded box.
  std::vector<std::array<float, 6>> box(count);
  for (std::size_t p = 0; p < count; ++p) {
    for (int c = 0; c < 3; ++c) {
      const bool empty = !(low[p][c] <= high[p][c]);
      box[p][c] = empty ? 0.0f : static_cast<float>(low[p][c]);
      box[p][3 + c] = empty ? 1.0f : std::max(static_cast<float>((high[p][c] - box[p][c]) / 65535.0), 1e-30f);
    }
    for (const float v : box[p]) put(out, v);
  }
  for (Index n = 0; n < nodes.rows(); ++n) {
    const auto& b = box[pieces.node_piece[n]];
    for (int c = 0; c < 3; ++c) {
      const double q = std::round((nodes(n, c) - b[c]) / b[3 + c]);
      put(out, static_cast<std::uint16_t>(std::isfinite(q) ? std::clamp(q, 0.0, 65535.0) : 0.0));
    }
  }
  pad4(out);
  return out;
}

std::string error_message(std::string_view message, std::optional<std::int64_t> seq) {
  Json reply = {{"type", "error"}, {"message", std::string(message)}};
  if (seq) reply["seq"] = *seq;
  return reply.dump(-1, ' ', false, Json::error_handler_t::replace);
}

}  // namespace tetcut::live
