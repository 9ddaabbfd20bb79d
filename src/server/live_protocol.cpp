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

#include "util/broken.hpp"
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

namespace {

// Appends an index: 16 bits where `narrow`, else 32.
void put_index(std::string& out, bool narrow, std::size_t i) {
  if (narrow) {
    put(out, static_cast<std::uint16_t>(i));
  } else {
    put(out, static_cast<std::uint32_t>(i));
  }
}

}  // namespace

TopologyEncoder::Messages TopologyEncoder::encode(std::uint32_t version, const std::vector<std::array<Index, 4>>& copy_nodes,
                                                  std::span<const Index> tet_parent, const NodePieces& pieces,
                                                  const MaterialSurface& surface) {
  const TriangleSurface& s = surface.surface;
  const std::size_t N = pieces.node_piece.size();
  const auto V = static_cast<std::size_t>(s.num_vertices());
  const Index F = s.num_triangles();
  const bool narrow_nodes = !wide_ && N <= std::size_t{1} << 16;
  const std::uint32_t flags = (narrow_nodes ? kNarrowNodes : 0u) | (wide_ ? 0u : kNarrowPatches);

  // 1. Each input tet's patch as it is now: its triangles are consecutive (the surface lists
  //    them by input tet), its vertices numbered in order of first use. O(V + F).
  // All patches in one buffer (no allocation per patch), `offsets[tet]..offsets[tet + 1]`.
  std::string& now = next_bytes_;
  std::vector<std::size_t>& offsets = next_offsets_;
  now.clear();
  offsets.assign(1, 0);
  const auto close_patches_up_to = [&](std::size_t tet) {
    while (offsets.size() <= tet) offsets.push_back(now.size());
  };
  local_.assign(V, -1);
  std::vector<Index> vertices;
  std::size_t total_vertices = 0, total_triangles = 0;
  for (Index first = 0; first < F;) {
    const Index tet = tet_parent[static_cast<std::size_t>(surface.triangle_tet[static_cast<std::size_t>(first)])];
    Index end = first;
    while (end < F && tet_parent[static_cast<std::size_t>(surface.triangle_tet[static_cast<std::size_t>(end)])] == tet) ++end;
    if (offsets.size() > static_cast<std::size_t>(tet) + 1) broken("live protocol", "the material surface's triangles are not grouped by input tet");
    close_patches_up_to(static_cast<std::size_t>(tet));
    vertices.clear();
    for (Index t = first; t < end; ++t) {
      for (int k = 0; k < 3; ++k) {
        const Index v = s.triangles(t, k);
        if (local_[static_cast<std::size_t>(v)] < 0) {
          local_[static_cast<std::size_t>(v)] = static_cast<std::int32_t>(vertices.size());
          vertices.push_back(v);
        }
      }
    }
    // The patch's size is known before it is written: one resize, then plain stores (a string
    // append a value costs several times more over ~10^5 values a cut).
    const bool narrow_local = !wide_ && vertices.size() <= std::size_t{1} << 16;
    const std::size_t nv = vertices.size(), nt = static_cast<std::size_t>(end - first);
    const auto round4 = [](std::size_t bytes) { return (bytes + 3) / 4 * 4; };
    const std::size_t start = now.size();
    now.resize(start + 12 + round4(nv * 4 * (narrow_nodes ? 2 : 4)) + round4(nv * 6) + round4(nt * 3 * (narrow_local ? 2 : 4)));
    char* out = now.data() + start;
    const auto store = [&out](auto value) {
      std::memcpy(out, &value, sizeof value);
      out += sizeof value;
    };
    const auto store_index = [&](bool narrow, std::size_t i) {
      if (narrow) {
        store(static_cast<std::uint16_t>(i));
      } else {
        store(static_cast<std::uint32_t>(i));
      }
    };
    const auto align = [&] {
      while ((out - now.data() - static_cast<std::ptrdiff_t>(start)) % 4 != 0) *out++ = '\0';
    };
    for (const std::size_t x : {static_cast<std::size_t>(tet), nv, nt}) store(static_cast<std::uint32_t>(x));
    for (const Index v : vertices) {
      for (const Index n : copy_nodes[static_cast<std::size_t>(surface.vertex_tet[static_cast<std::size_t>(v)])]) {
        store_index(narrow_nodes, static_cast<std::size_t>(n));
      }
    }
    align();
    // Weights 0..2 in units of 1/65535: a vertex is placed within 1e-5 of its copy's size, and
    // its weights take 6 bytes, not 16.
    for (const Index v : vertices) {
      for (int k = 0; k < 3; ++k) {
        // Rounded to nearest (non-negative, so + 0.5 and truncation; lround is a call).
        store(static_cast<std::uint16_t>(std::clamp(surface.vertex_weights(v, k), 0.0, 1.0) * 65535.0 + 0.5));
      }
    }
    align();
    for (Index t = first; t < end; ++t) {
      for (int k = 0; k < 3; ++k) store_index(narrow_local, static_cast<std::size_t>(local_[static_cast<std::size_t>(s.triangles(t, k))]));
    }
    align();
    if (out != now.data() + now.size()) broken("live protocol", "a patch's size was miscounted");
    for (const Index v : vertices) local_[static_cast<std::size_t>(v)] = -1;
    total_vertices += vertices.size();
    total_triangles += static_cast<std::size_t>(end - first);
    offsets.push_back(now.size());
    first = end;
  }
  close_patches_up_to(offsets_.empty() ? 0 : offsets_.size() - 1);
  const std::size_t tets = offsets.size() - 1;
  const auto patch = [](const std::string& bytes, const std::vector<std::size_t>& at, std::size_t tet) {
    return tet + 1 < at.size() ? std::string_view(bytes).substr(at[tet], at[tet + 1] - at[tet]) : std::string_view();
  };

  // 2. The whole topology, and what changed since the last version: the patches whose bytes
  //    differ (a removed one as its tet with no vertices or triangles). O(T + bytes).
  const auto message = [&](std::uint32_t base, std::size_t patches, std::size_t bytes) {
    std::string out;
    out.reserve(kTopologyHeader + 4 * N + 4 * pieces.count + bytes);
    for (const std::uint32_t x : {kTopologyMessage, version, base, static_cast<std::uint32_t>(N), pieces.count, static_cast<std::uint32_t>(patches),
                                  static_cast<std::uint32_t>(total_vertices), static_cast<std::uint32_t>(total_triangles), flags, 0u}) {
      put(out, x);
    }
    for (const std::uint32_t p : pieces.node_piece) put_index(out, narrow_nodes, p);
    pad4(out);
    for (std::uint32_t p = 0; p < pieces.count; ++p) {
      const auto rgb = render::piece_colour(static_cast<Index>(p));
      out.append(reinterpret_cast<const char*>(rgb.data()), 3);
      out.push_back('\0');
    }
    return out;
  };
  std::size_t full_patches = 0;
  for (std::size_t tet = 0; tet < tets; ++tet) full_patches += offsets[tet + 1] > offsets[tet] ? 1 : 0;
  Messages messages;
  messages.version = version;
  messages.full = message(0, full_patches, now.size());
  messages.full += now;
  if (last_version_ != 0 && version == last_version_ + 1) {
    std::vector<std::size_t> changed;
    std::size_t changed_bytes = 0;
    for (std::size_t tet = 0; tet < tets; ++tet) {
      const std::string_view p = patch(now, offsets, tet);
      if (p == patch(bytes_, offsets_, tet)) continue;
      changed.push_back(tet);
      changed_bytes += p.empty() ? 12 : p.size();
    }
    messages.change = message(last_version_, changed.size(), changed_bytes);
    for (const std::size_t tet : changed) {
      const std::string_view p = patch(now, offsets, tet);
      if (p.empty()) {
        for (const std::uint32_t x : {static_cast<std::uint32_t>(tet), 0u, 0u}) put(messages.change, x);
      } else {
        messages.change += p;
      }
    }
  }
  std::swap(bytes_, now);  // the buffers are kept: no allocation and page faults per cut
  std::swap(offsets_, offsets);
  last_version_ = version;
  return messages;
}

TopologyEncoder::Messages TopologyEncoder::encode(std::uint32_t version, Session& session, NodePieces* pieces) {
  const Cutter& cutter = session.cutter();
  *pieces = node_pieces(cutter.tet_nodes(), cutter.num_nodes());
  return encode(version, cutter.tet_nodes(), cutter.tet_parent(), *pieces, session.surface());
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
      // A flat axis has no extent to divide: any positive step (in float) quantises it to 0.
      constexpr float kFlatStep = 1e-30f;
      box[p][3 + c] = empty ? 1.0f : std::max(static_cast<float>((high[p][c] - box[p][c]) / 65535.0), kFlatStep);
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
