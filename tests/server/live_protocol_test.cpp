// The live session's messages: what a page may send (and the errors for what it may not), and
// the binary frames and topology the page decodes, checked by decoding them here.

#include <tetcut/cutter.hpp>
#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>

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

TEST(LiveProtocol, TopologyHoldsTheSurfaceEmbeddedInItsCopies) {
  Cutter cutter(make_grid(Box{}, {2, 2, 2}, 5));
  const MaterialSurface surface = cutter.surface();
  const NodePieces pieces = node_pieces(cutter.tet_nodes(), cutter.num_nodes());
  const std::string topology = encode_topology(5, cutter.tet_nodes(), pieces, surface);
  const auto T = cutter.tet_nodes().size(), N = static_cast<std::size_t>(cutter.num_nodes());
  const auto V = static_cast<std::size_t>(surface.surface.num_vertices()), F = static_cast<std::size_t>(surface.surface.num_triangles());
  EXPECT_EQ(read_at<std::uint32_t>(topology, 0), kTopologyMessage);
  EXPECT_EQ(read_at<std::uint32_t>(topology, 4), 5u);
  EXPECT_EQ(read_at<std::uint32_t>(topology, 8), T);
  EXPECT_EQ(read_at<std::uint32_t>(topology, 12), N);
  EXPECT_EQ(read_at<std::uint32_t>(topology, 16), V);
  EXPECT_EQ(read_at<std::uint32_t>(topology, 20), F);
  EXPECT_EQ(read_at<std::uint32_t>(topology, 24), 1u);
  const std::size_t expected = 32 + 16 * T + 4 * N + 4 * V + 16 * V + 12 * F + 3 * V;
  EXPECT_EQ(topology.size(), (expected + 3) / 4 * 4);
  // The page's placement of vertex v (weights times its copy's corners) is its rest position.
  const std::size_t copy_at = 32 + 16 * T + 4 * N, weights_at = copy_at + 4 * V, triangles_at = weights_at + 16 * V;
  const Points& rest = cutter.input().rest();
  for (std::size_t v = 0; v < V; v += 7) {
    const auto copy = read_at<std::uint32_t>(topology, copy_at + 4 * v);
    Vec3 placed = Vec3::Zero();
    for (int k = 0; k < 4; ++k) {
      const auto node = read_at<std::uint32_t>(topology, 32 + 16 * copy + 4 * k);
      placed += read_at<float>(topology, weights_at + 16 * v + 4 * k) * rest.row(cutter.node_parent()[node]).transpose();
    }
    EXPECT_LT((placed - surface.surface.vertices.row(static_cast<Index>(v)).transpose()).norm(), 1e-6) << v;
  }
  EXPECT_EQ(read_at<std::uint32_t>(topology, triangles_at), static_cast<std::uint32_t>(surface.surface.triangles(0, 0)));
}

}  // namespace
}  // namespace tetcut::live
