#pragma once
// The live session's wire format (tetcut serve and its page), kept apart from the networking so
// that it is tested on its own.
//
// Server to page, binary (little-endian, every section 4-byte aligned):
//   topology  u32 kind = 1, version, copies T, nodes N, vertices V, triangles F, pieces P, flags
//             T x 4 node  each tet copy's nodes
//             N node      each node's piece (pieces: nodes connected through copies, most nodes first)
//             V copy      the copy each surface vertex is embedded in
//             V x 3 u16   its barycentric weights 0..2 in that copy, in units of 1/65535 (the
//                         fourth is one less their sum)
//             F x 3 vert  the material surface's triangles (outward)
//             P x 4 u8    each piece's colour (sRGB, then 0)
//             A node, copy or vert index is a u16 where flags has kNarrowNodes, kNarrowCopies or
//             kNarrowVertices (that count is at most 65536), else a u32: the default scene's
//             topology is 1 MB, not the 2.4 MB of 32-bit indices and float weights.
//   frame     u32 kind = 2, topology version, step, N, P, 0; f64 simulated time;
//             P x 6 f32   each piece's box: min[3], step[3]
//             N x 3 u16   node positions, quantised in their piece's box: x = min + q step
// Boxes are per piece so that a piece falling away does not coarsen the others' positions.
// The page places the surface's vertices from the nodes (weights times corners), so a frame is
// 6 bytes a node (16 KB for the default scene's 2.6k nodes), however fine the surface. Topology
// goes out only when a cut changed it (and to a page that joins).
//
// Page to server, JSON text, at most kMaxClientMessage bytes, with an optional increasing "seq"
// that replies echo:
//   {"type": "blade", "a": [x,y,z], "b": [x,y,z]}     the scalpel's edge now (world space)
//   {"type": "lift"}                                  the blade left the material
//   {"type": "grab", "point": [x,y,z], "stiffness"?}  a hook; answered {"type":"grabbed","hook":k}
//   {"type": "move_hook", "hook": k, "target": [x,y,z]}
//   {"type": "release", "hook": k}
//   {"type": "pin" | "unpin", "point": [x,y,z], "radius": r}
//   {"type": "pause", "paused": true|false}
//   {"type": "reset"}
// Server to page, JSON text: {"type": "stats", ...} (as GET /api/state), {"type": "error",
// "message", "seq"?}, {"type": "grabbed", ...}, {"type": "reset"} (hooks are gone), and to the
// page whose blade pose changed the mesh {"type": "cut", "seq", "version"}: the topology version
// that shows it, sent before that topology.

#include <tetcut/cutter.hpp>
#include <tetcut/session.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tetcut::live {

inline constexpr std::uint32_t kTopologyMessage = 1;
inline constexpr std::uint32_t kFrameMessage = 2;
/// A topology's flags: which of its indices are 16-bit.
inline constexpr std::uint32_t kNarrowNodes = 1, kNarrowCopies = 2, kNarrowVertices = 4;
/// Page messages longer than this get an error reply (the longest valid one is ~150 bytes).
inline constexpr std::size_t kMaxClientMessage = 16 * 1024;

/// What a page asked for, checked for shape and finiteness (the session checks the rest).
struct ClientCommand {
  enum class Kind { kEvent, kPause, kReset };
  Kind kind = Kind::kEvent;
  SessionEvent event;  ///< kEvent (its time is the session's when applied)
  bool paused = false;  ///< kPause
  std::optional<std::int64_t> seq;
};

/// Parses one page message. Throws Error(kInvalidArgument) with a message for the page
/// ("not valid JSON: ...", "unknown message type 'x'", "'a' must be 3 finite numbers", ...).
ClientCommand parse_client_message(std::string_view text);

/// The pieces of a cut mesh: nodes connected through tet copies, numbered by size (most nodes
/// first, ties by lowest node). O(T).
struct NodePieces {
  std::vector<std::uint32_t> node_piece;
  std::uint32_t count = 0;
};
NodePieces node_pieces(const std::vector<std::array<Index, 4>>& copy_nodes, Index num_nodes);

/// Where a topology message's sections start (bytes) and its flags, for these counts; `wide`:
/// 32-bit indices whatever the counts.
struct TopologyLayout {
  std::uint32_t flags = 0;
  std::size_t copy_nodes = 0, node_pieces = 0, vertex_copies = 0, weights = 0, triangles = 0;
};
TopologyLayout topology_layout(std::size_t copies, std::size_t nodes, std::size_t vertices, bool wide = false);

/// A topology message: the copies (`copy_nodes`, as Cutter::tet_nodes), their pieces, the
/// surface, and the pieces' colours. O(T + N + V + F).
std::string encode_topology(std::uint32_t version, const std::vector<std::array<Index, 4>>& copy_nodes,
                            const NodePieces& pieces, const MaterialSurface& surface, bool wide = false);
/// The topology message of a session as it stands (its cutter's copies and its material
/// surface); sets `pieces`, which its frames quantise by.
std::string encode_topology(std::uint32_t version, Session& session, NodePieces* pieces);
/// A frame message: node positions quantised to 16 bits in their piece's bounding box.
std::string encode_frame(std::uint32_t version, std::uint32_t step, double time, const Points& nodes, const NodePieces& pieces);

/// The JSON of an error reply.
std::string error_message(std::string_view message, std::optional<std::int64_t> seq);

}  // namespace tetcut::live
