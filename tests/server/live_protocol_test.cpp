// The live session's messages: what a page may send (and the errors for what it may not), and
// the binary frames and topology the page decodes, checked by decoding them here.

#include <tetcut/cutter.hpp>
#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/render.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
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
struct DecodedPatch {
  std::vector<std::array<std::uint32_t, 4>> nodes;
  std::vector<std::array<double, 4>> weights;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  bool operator==(const DecodedPatch&) const = default;
};
struct DecodedTopology {
  std::uint32_t version = 0, base = 0, flags = 0, pieces = 0, vertices = 0, triangles = 0;
  std::vector<std::uint32_t> node_piece;
  std::vector<std::array<std::uint8_t, 3>> colours;
  std::vector<std::pair<std::uint32_t, DecodedPatch>> patches;  // in message order
};

DecodedTopology decode_topology(const std::string& m) {
  DecodedTopology d;
  EXPECT_EQ(read_at<std::uint32_t>(m, 0), kTopologyMessage);
  d.version = read_at<std::uint32_t>(m, 4);
  d.base = read_at<std::uint32_t>(m, 8);
  const std::size_t N = read_at<std::uint32_t>(m, 12);
  d.pieces = read_at<std::uint32_t>(m, 16);
  const std::size_t K = read_at<std::uint32_t>(m, 20);
  d.vertices = read_at<std::uint32_t>(m, 24);
  d.triangles = read_at<std::uint32_t>(m, 28);
  d.flags = read_at<std::uint32_t>(m, 32);
  EXPECT_EQ(read_at<std::uint32_t>(m, 36), 0u);
  std::size_t at = kTopologyHeader;
  const auto align = [&] { at = (at + 3) / 4 * 4; };
  const auto index = [&](bool narrow) -> std::uint32_t {
    const std::uint32_t i = narrow ? read_at<std::uint16_t>(m, at) : read_at<std::uint32_t>(m, at);
    at += narrow ? 2 : 4;
    return i;
  };
  const bool narrow_nodes = (d.flags & kNarrowNodes) != 0;
  for (std::size_t n = 0; n < N; ++n) d.node_piece.push_back(index(narrow_nodes));
  align();
  for (std::uint32_t p = 0; p < d.pieces; ++p, at += 4) {
    d.colours.push_back({read_at<std::uint8_t>(m, at), read_at<std::uint8_t>(m, at + 1), read_at<std::uint8_t>(m, at + 2)});
    EXPECT_EQ(read_at<std::uint8_t>(m, at + 3), 0);
  }
  for (std::size_t k = 0; k < K; ++k) {
    const std::uint32_t tet = index(false), n = index(false), f = index(false);
    DecodedPatch patch;
    patch.nodes.resize(n);
    for (auto& corner : patch.nodes) {
      for (auto& node : corner) node = index(narrow_nodes);
    }
    align();
    for (std::uint32_t v = 0; v < n; ++v) {
      std::array<double, 4> w{};
      for (int c = 0; c < 3; ++c, at += 2) w[static_cast<std::size_t>(c)] = read_at<std::uint16_t>(m, at) / 65535.0;
      w[3] = 1 - w[0] - w[1] - w[2];
      patch.weights.push_back(w);
    }
    align();
    const bool narrow_local = (d.flags & kNarrowPatches) != 0 && n <= 65536;
    patch.triangles.resize(f);
    for (auto& t : patch.triangles) {
      for (auto& v : t) {
        v = index(narrow_local);
        EXPECT_LT(v, n);
      }
    }
    align();
    d.patches.emplace_back(tet, std::move(patch));
  }
  EXPECT_EQ(at, m.size());  // nothing left over, nothing missing
  return d;
}

// What the page holds: the patches by input tet, after a whole topology and the changes since.
using PagePatches = std::map<std::uint32_t, DecodedPatch>;
void apply_topology(const DecodedTopology& d, PagePatches* page) {
  if (d.base == 0) page->clear();
  for (const auto& [tet, patch] : d.patches) {
    if (patch.triangles.empty()) {
      EXPECT_TRUE(patch.nodes.empty());
      EXPECT_EQ(page->erase(tet), 1u) << "removes a patch the page does not have: " << tet;
    } else {
      (*page)[tet] = patch;
    }
  }
  std::size_t vertices = 0, triangles = 0;
  for (const auto& [tet, patch] : *page) {
    vertices += patch.nodes.size();
    triangles += patch.triangles.size();
  }
  EXPECT_EQ(vertices, d.vertices);
  EXPECT_EQ(triangles, d.triangles);
}

TriangleSurface plane_at_x(double x) {
  TriangleSurface plane;
  plane.vertices.resize(4, 3);
  plane.vertices << x, -1, -1, x, 2, -1, x, 2, 2, x, -1, 2;
  plane.triangles.resize(2, 3);
  plane.triangles << 0, 1, 2, 0, 2, 3;
  return plane;
}

TEST(LiveProtocol, TopologyHoldsTheSurfaceEmbeddedInItsCopies) {
  // A block cut in two by a plane at x = 0.4: two pieces, each with its colour.
  Cutter cutter(make_grid(Box{}, {3, 3, 3}, 5));
  cutter.cut(plane_at_x(0.4));
  const MaterialSurface surface = cutter.surface();
  const NodePieces pieces = node_pieces(cutter.tet_nodes(), cutter.num_nodes());
  ASSERT_EQ(pieces.count, 2u);
  const Points& rest = cutter.input().rest();
  for (const bool wide : {false, true}) {
    SCOPED_TRACE(wide ? "32-bit indices" : "16-bit indices");
    TopologyEncoder encoder(wide);
    const TopologyEncoder::Messages messages = encoder.encode(5, cutter.tet_nodes(), cutter.tet_parent(), pieces, surface);
    EXPECT_TRUE(messages.change.empty());  // nothing to change from
    const DecodedTopology d = decode_topology(messages.full);
    EXPECT_EQ(d.version, 5u);
    EXPECT_EQ(d.base, 0u);
    EXPECT_EQ(d.flags, wide ? 0u : kNarrowNodes | kNarrowPatches);
    EXPECT_EQ(d.node_piece, pieces.node_piece);
    for (std::uint32_t p = 0; p < d.pieces; ++p) EXPECT_EQ(d.colours[p], render::piece_colour(static_cast<Index>(p)));
    EXPECT_EQ(d.triangles, static_cast<std::uint32_t>(surface.surface.num_triangles()));
    // The patches, in tet order, list the surface's triangles in its order; the page's placement
    // of each corner (weights times nodes) is the vertex's rest position, to the weights'
    // quantisation (a copy here is 1/3 across).
    Index row = 0;
    std::uint32_t previous_tet = 0;
    for (const auto& [tet, patch] : d.patches) {
      EXPECT_TRUE(row == 0 || tet > previous_tet);
      previous_tet = tet;
      for (const auto& triangle : patch.triangles) {
        ASSERT_LT(row, surface.surface.num_triangles());
        EXPECT_EQ(static_cast<std::uint32_t>(cutter.tet_parent()[static_cast<std::size_t>(surface.triangle_tet[static_cast<std::size_t>(row)])]), tet);
        for (int k = 0; k < 3; ++k) {
          const std::uint32_t v = triangle[static_cast<std::size_t>(k)];
          Vec3 placed = Vec3::Zero();
          for (int c = 0; c < 4; ++c) {
            placed += patch.weights[v][static_cast<std::size_t>(c)] * rest.row(cutter.node_parent()[patch.nodes[v][static_cast<std::size_t>(c)]]).transpose();
          }
          EXPECT_LT((placed - surface.surface.vertices.row(surface.surface.triangles(row, k)).transpose()).norm(), 2e-5) << row;
        }
        ++row;
      }
    }
    EXPECT_EQ(row, surface.surface.num_triangles());
  }
}

TEST(LiveProtocol, ATopologyChangeCarriesThePatchesThatChanged) {
  const TetMesh block = make_grid(Box{}, {4, 4, 4}, 5);
  Cutter cutter(block);
  TopologyEncoder encoder;
  const auto encode = [&](std::uint32_t version, Cutter& c) {
    return encoder.encode(version, c.tet_nodes(), c.tet_parent(), node_pieces(c.tet_nodes(), c.num_nodes()), c.surface());
  };
  PagePatches page;
  apply_topology(decode_topology(encode(1, cutter).full), &page);
  // Two cuts, each sent as the change from the version before: applied to the page's patches,
  // each gives what the whole topology of its version gives, in fewer bytes.
  std::uint32_t version = 1;
  for (const double x : {0.4, 0.7}) {
    SCOPED_TRACE(x);
    cutter.cut(plane_at_x(x));
    const TopologyEncoder::Messages messages = encode(++version, cutter);
    ASSERT_FALSE(messages.change.empty());
    const DecodedTopology change = decode_topology(messages.change);
    EXPECT_EQ(change.base, version - 1);
    EXPECT_EQ(change.version, version);
    EXPECT_LT(messages.change.size(), messages.full.size());
    apply_topology(change, &page);
    PagePatches whole;
    apply_topology(decode_topology(messages.full), &whole);
    EXPECT_EQ(page, whole);
    // The cut's plane passes through one layer of tets: the patches of tets far from it are not sent.
    for (const auto& [tet, patch] : change.patches) {
      double low = 1, high = 0;
      for (int k = 0; k < 4; ++k) {
        low = std::min(low, block.rest()(block.tets()(tet, k), 0));
        high = std::max(high, block.rest()(block.tets()(tet, k), 0));
      }
      EXPECT_TRUE(low <= x + 0.25 && high >= x - 0.25) << "tet " << tet << " spans x in [" << low << ", " << high << "]";
    }
  }
  // Back to the uncut block (a reset): the cut's patches inside the block are removed.
  Cutter fresh(block);
  const TopologyEncoder::Messages reset = encode(++version, fresh);
  const DecodedTopology change = decode_topology(reset.change);
  EXPECT_TRUE(std::any_of(change.patches.begin(), change.patches.end(), [](const auto& p) { return p.second.triangles.empty(); }));
  apply_topology(change, &page);
  PagePatches whole;
  apply_topology(decode_topology(reset.full), &whole);
  EXPECT_EQ(page, whole);
  // A version that does not follow the last one has no change: the pages get it whole.
  EXPECT_TRUE(encode(version + 2, fresh).change.empty());
}

}  // namespace
}  // namespace tetcut::live
