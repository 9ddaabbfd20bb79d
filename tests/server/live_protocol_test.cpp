// The live session's messages: what a page may send (and the errors for what it may not), and
// the binary frames and topology the page decodes, checked by decoding them here.

#include <tetcut/cutter.hpp>
#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/render.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "server/live_protocol.hpp"

namespace tetcut::live {
namespace {

using ::testing::HasSubstr;

std::string refusal(const std::string& text) {
  try {
    parse_client_message(text);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInvalidArgument);
    return e.what();
  }
  return "accepted";
}

TEST(LiveProtocol, ReadsEveryMessageType) {
  const ClientCommand blade = parse_client_message(R"({"type": "blade", "a": [0, 1, 2], "b": [3, 4, 5.5], "seq": 7})");
  EXPECT_EQ(blade.kind, ClientCommand::Kind::kEvent);
  EXPECT_EQ(blade.event.kind, SessionEvent::Kind::kBlade);
  EXPECT_EQ(blade.event.pose.b, Vec3(3, 4, 5.5));
  EXPECT_EQ(blade.seq, 7);
  EXPECT_EQ(parse_client_message(R"({"type": "lift"})").event.kind, SessionEvent::Kind::kLiftBlade);
  const ClientCommand grab = parse_client_message(R"({"type": "grab", "point": [1, 2, 3], "stiffness": 50})");
  EXPECT_EQ(grab.event.kind, SessionEvent::Kind::kGrab);
  EXPECT_EQ(grab.event.stiffness, 50);
  EXPECT_FALSE(grab.seq.has_value());
  const ClientCommand move = parse_client_message(R"({"type": "move_hook", "hook": 2, "target": [0, 0, 1]})");
  EXPECT_EQ(move.event.hook, 2);
  EXPECT_EQ(move.event.point, Vec3(0, 0, 1));
  EXPECT_EQ(parse_client_message(R"({"type": "release", "hook": 0})").event.kind, SessionEvent::Kind::kRelease);
  const ClientCommand pin = parse_client_message(R"({"type": "unpin", "point": [0, 0, 0], "radius": 0.5})");
  EXPECT_EQ(pin.event.kind, SessionEvent::Kind::kUnpin);
  EXPECT_EQ(pin.event.radius, 0.5);
  const ClientCommand pause = parse_client_message(R"({"type": "pause", "paused": true})");
  EXPECT_EQ(pause.kind, ClientCommand::Kind::kPause);
  EXPECT_TRUE(pause.paused);
  EXPECT_EQ(parse_client_message(R"({"type": "reset"})").kind, ClientCommand::Kind::kReset);
}

TEST(LiveProtocol, RefusesWhatIsNotAMessage) {
  EXPECT_THAT(refusal("{\"type\": \"blade\", "), HasSubstr("not valid JSON"));
  EXPECT_THAT(refusal("[1, 2]"), HasSubstr("a JSON object"));
  EXPECT_THAT(refusal(R"({"a": 1})"), HasSubstr("needs a 'type'"));
  EXPECT_THAT(refusal(R"({"type": "explode"})"), HasSubstr("unknown message type \"explode\""));
  EXPECT_THAT(refusal(R"({"type": "blade", "a": [0, 0], "b": [0, 0, 0]})"), HasSubstr("'a' must be 3 finite numbers"));
  EXPECT_THAT(refusal(R"({"type": "blade", "a": [0, 0, "x"], "b": [0, 0, 0]})"), HasSubstr("'a' must be 3 finite numbers"));
  EXPECT_THAT(refusal(R"({"type": "blade", "a": [0, 0, 1e999], "b": [0, 0, 0]})"), HasSubstr("not valid JSON"));  // overflows
  EXPECT_THAT(refusal(R"({"type": "blade", "a": [0, 0, NaN], "b": [0, 0, 0]})"), HasSubstr("not valid JSON"));
  EXPECT_THAT(refusal(R"({"type": "grab"})"), HasSubstr("missing 'point'"));
  EXPECT_THAT(refusal(R"({"type": "grab", "point": [0, 0, 0], "stiffness": -1})"), HasSubstr("must not be negative"));
  EXPECT_THAT(refusal(R"({"type": "move_hook", "hook": -1, "target": [0, 0, 0]})"), HasSubstr("a hook's number"));
  EXPECT_THAT(refusal(R"({"type": "move_hook", "hook": 1.5, "target": [0, 0, 0]})"), HasSubstr("a hook's number"));
  EXPECT_THAT(refusal(R"({"type": "pin", "point": [0, 0, 0], "radius": 0})"), HasSubstr("'radius' must be positive"));
  EXPECT_THAT(refusal(R"({"type": "pause", "paused": 1})"), HasSubstr("true or false"));
  EXPECT_THAT(refusal(R"({"type": "lift", "seq": -3})"), HasSubstr("non-negative integer"));
  EXPECT_THAT(refusal(std::string(kMaxClientMessage + 1, ' ')), HasSubstr("the limit is 16384"));
}

template <typename T>
T read_at(const std::string& bytes, std::size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}

TEST(LiveProtocol, PiecesAreTheNodesConnectedThroughCopies) {
  // Three copies: 0 and 1 share nodes 1-3; copy 2 stands alone on nodes 4-7; node 8 is in none.
  const std::vector<std::array<Index, 4>> copies = {{0, 1, 2, 3}, {1, 2, 3, 4}, {5, 6, 7, 8}};
  const NodePieces pieces = node_pieces(copies, 10);
  EXPECT_EQ(pieces.count, 3u);  // {0..4}, {5..8}, {9}
  EXPECT_EQ(pieces.node_piece[0], 0u);  // the most nodes first
  EXPECT_EQ(pieces.node_piece[4], 0u);
  EXPECT_EQ(pieces.node_piece[5], 1u);
  EXPECT_EQ(pieces.node_piece[8], 1u);
  EXPECT_EQ(pieces.node_piece[9], 2u);
}

TEST(LiveProtocol, FramesQuantiseEachPieceInItsOwnBox) {
  // Two pieces far apart: each node comes back within half a step of its own piece's box.
  const std::vector<std::array<Index, 4>> copies = {{0, 1, 2, 3}, {4, 5, 6, 7}};
  const NodePieces pieces = node_pieces(copies, 8);
  Points nodes(8, 3);
  nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1,  // a unit tet
      1000, 0, -500, 1000.001, 0, -500, 1000, 0.001, -500, 1000, 0, -499.999;  // a tiny one far away
  const std::string frame = encode_frame(3, 42, 1.5, nodes, pieces);
  EXPECT_EQ(frame.size() % 4, 0u);
  EXPECT_EQ(read_at<std::uint32_t>(frame, 0), kFrameMessage);
  EXPECT_EQ(read_at<std::uint32_t>(frame, 4), 3u);
  EXPECT_EQ(read_at<std::uint32_t>(frame, 8), 42u);
  EXPECT_EQ(read_at<std::uint32_t>(frame, 12), 8u);
  EXPECT_EQ(read_at<std::uint32_t>(frame, 16), 2u);
  EXPECT_EQ(read_at<double>(frame, 24), 1.5);
  ASSERT_GE(frame.size(), 32 + 2 * 24 + 8 * 6u);
  for (Index n = 0; n < 8; ++n) {
    const std::size_t box = 32 + 24 * pieces.node_piece[n];
    for (int c = 0; c < 3; ++c) {
      const float min = read_at<float>(frame, box + 4 * c), step = read_at<float>(frame, box + 12 + 4 * c);
      const double x = min + read_at<std::uint16_t>(frame, 32 + 48 + 6 * n + 2 * c) * static_cast<double>(step);
      // Half a step, and float's rounding of the box corner.
      EXPECT_NEAR(x, nodes(n, c), 0.5 * step + 1e-7 * std::abs(nodes(n, c)) + 1e-12) << n << "," << c;
    }
  }
  // The far tiny piece keeps its detail: its steps are about 1e-3 / 65535.
  EXPECT_LT(read_at<float>(frame, 32 + 24 + 12), 1e-7);
}

// A topology message read back as the page reads it: by its header's counts and flags.
struct DecodedTopology {
  std::uint32_t version = 0, flags = 0, pieces = 0;
  std::vector<std::array<std::uint32_t, 4>> copy_nodes;
  std::vector<std::uint32_t> node_piece, vertex_copy;
  std::vector<std::array<double, 4>> weights;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<std::array<std::uint8_t, 3>> colours;
};

DecodedTopology decode_topology(const std::string& m) {
  DecodedTopology d;
  EXPECT_EQ(read_at<std::uint32_t>(m, 0), kTopologyMessage);
  d.version = read_at<std::uint32_t>(m, 4);
  const std::size_t T = read_at<std::uint32_t>(m, 8), N = read_at<std::uint32_t>(m, 12), V = read_at<std::uint32_t>(m, 16),
                    F = read_at<std::uint32_t>(m, 20);
  d.pieces = read_at<std::uint32_t>(m, 24);
  d.flags = read_at<std::uint32_t>(m, 28);
  std::size_t at = 32;
  const auto align = [&] { at = (at + 3) / 4 * 4; };
  const auto index = [&](std::uint32_t flag) -> std::uint32_t {
    const std::uint32_t i = d.flags & flag ? read_at<std::uint16_t>(m, at) : read_at<std::uint32_t>(m, at);
    at += d.flags & flag ? 2 : 4;
    return i;
  };
  d.copy_nodes.resize(T);
  for (auto& copy : d.copy_nodes) {
    for (auto& n : copy) n = index(kNarrowNodes);
  }
  align();
  for (std::size_t n = 0; n < N; ++n) d.node_piece.push_back(index(kNarrowNodes));
  align();
  for (std::size_t v = 0; v < V; ++v) d.vertex_copy.push_back(index(kNarrowCopies));
  align();
  for (std::size_t v = 0; v < V; ++v) {
    std::array<double, 4> w{};
    for (int k = 0; k < 3; ++k, at += 2) w[static_cast<std::size_t>(k)] = read_at<std::uint16_t>(m, at) / 65535.0;
    w[3] = 1 - w[0] - w[1] - w[2];
    d.weights.push_back(w);
  }
  align();
  d.triangles.resize(F);
  for (auto& t : d.triangles) {
    for (auto& v : t) v = index(kNarrowVertices);
  }
  align();
  for (std::uint32_t p = 0; p < d.pieces; ++p, at += 4) {
    d.colours.push_back({read_at<std::uint8_t>(m, at), read_at<std::uint8_t>(m, at + 1), read_at<std::uint8_t>(m, at + 2)});
    EXPECT_EQ(read_at<std::uint8_t>(m, at + 3), 0);
  }
  EXPECT_EQ(at, m.size());  // nothing left over, nothing missing
  return d;
}

TEST(LiveProtocol, TopologyHoldsTheSurfaceEmbeddedInItsCopies) {
  // A block cut in two by a plane at x = 0.4: two pieces, each with its colour.
  Cutter cutter(make_grid(Box{}, {3, 3, 3}, 5));
  TriangleSurface plane;
  plane.vertices.resize(4, 3);
  plane.vertices << 0.4, -1, -1, 0.4, 2, -1, 0.4, 2, 2, 0.4, -1, 2;
  plane.triangles.resize(2, 3);
  plane.triangles << 0, 1, 2, 0, 2, 3;
  cutter.cut(plane);
  const MaterialSurface surface = cutter.surface();
  const NodePieces pieces = node_pieces(cutter.tet_nodes(), cutter.num_nodes());
  ASSERT_EQ(pieces.count, 2u);
  const Points& rest = cutter.input().rest();
  for (const bool wide : {false, true}) {
    SCOPED_TRACE(wide ? "32-bit indices" : "16-bit indices");
    const std::string topology = encode_topology(5, cutter.tet_nodes(), pieces, surface, wide);
    const DecodedTopology d = decode_topology(topology);
    EXPECT_EQ(d.version, 5u);
    EXPECT_EQ(d.flags, wide ? 0u : kNarrowNodes | kNarrowCopies | kNarrowVertices);
    const TopologyLayout layout = topology_layout(cutter.tet_nodes().size(), pieces.node_piece.size(),
                                                  static_cast<std::size_t>(surface.surface.num_vertices()), wide);
    EXPECT_EQ(layout.flags, d.flags);
    EXPECT_EQ(read_at<std::uint32_t>(topology, layout.triangles) & (wide ? 0xffffffffu : 0xffffu),
              static_cast<std::uint32_t>(surface.surface.triangles(0, 0)));
    ASSERT_EQ(d.copy_nodes.size(), cutter.tet_nodes().size());
    for (std::size_t t = 0; t < d.copy_nodes.size(); ++t) {
      for (int k = 0; k < 4; ++k) EXPECT_EQ(d.copy_nodes[t][static_cast<std::size_t>(k)], static_cast<std::uint32_t>(cutter.tet_nodes()[t][static_cast<std::size_t>(k)]));
    }
    EXPECT_EQ(d.node_piece, pieces.node_piece);
    ASSERT_EQ(d.triangles.size(), static_cast<std::size_t>(surface.surface.num_triangles()));
    for (std::size_t t = 0; t < d.triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) EXPECT_EQ(d.triangles[t][static_cast<std::size_t>(k)], static_cast<std::uint32_t>(surface.surface.triangles(static_cast<Index>(t), k)));
    }
    for (std::uint32_t p = 0; p < d.pieces; ++p) EXPECT_EQ(d.colours[p], render::piece_colour(static_cast<Index>(p)));
    // The page's placement of every vertex (weights times its copy's corners) is its rest
    // position, to the weights' quantisation (a copy here is 1/3 across).
    ASSERT_EQ(d.vertex_copy.size(), static_cast<std::size_t>(surface.surface.num_vertices()));
    for (std::size_t v = 0; v < d.vertex_copy.size(); ++v) {
      EXPECT_EQ(d.vertex_copy[v], static_cast<std::uint32_t>(surface.vertex_tet[v]));
      Vec3 placed = Vec3::Zero();
      for (int k = 0; k < 4; ++k) {
        const auto node = d.copy_nodes[d.vertex_copy[v]][static_cast<std::size_t>(k)];
        placed += d.weights[v][static_cast<std::size_t>(k)] * rest.row(cutter.node_parent()[node]).transpose();
      }
      EXPECT_LT((placed - surface.surface.vertices.row(static_cast<Index>(v)).transpose()).norm(), 2e-5) << v;
    }
  }
  // 16-bit indices where the counts fit, whatever the others.
  EXPECT_EQ(topology_layout(10, 65536, 65537).flags, kNarrowNodes | kNarrowCopies);
  EXPECT_EQ(topology_layout(70000, 10, 10).flags, kNarrowNodes | kNarrowVertices);
}

}  // namespace
}  // namespace tetcut::live
