#pragma once
// The live session's wire format (tetcut serve and its page), kept apart from the networking so
// that it is tested on its own.
//
// Server to page, binary (little-endian, every section 4-byte aligned):
//   topology  u32 kind = 1, version, base, nodes N, pieces P, patches K, vertices V, triangles F,
//             flags, 0
//             N node      each node's piece (pieces: nodes connected through copies, most nodes first)
//             P x 4 u8    each piece's colour (sRGB, then 0)
//             K patches   the material surface inside one input tet each:
//                         u32 tet, vertices n, triangles m
//                         n x 4 node  each vertex's four nodes (those of the copy it is embedded in)
//                         n x 3 u16   its weights for the first three, in units of 1/65535 (the
//                                     fourth is one less their sum)
//                         m x 3 local its triangles (outward), indices into the patch's vertices
//             Base 0: the whole topology; the patches are all there are. Otherwise the patches
//             that changed since version `base` (which the page holds): each replaces the patch
//             of its tet, and one with no triangles removes it; V and F count the surface after.
//             A node index is a u16 where flags has kNarrowNodes (N at most 65536), else a u32;
//             a local index a u16 where flags has kNarrowPatches and the patch has at most 65536
//             vertices, else a u32.
//   frame     u32 kind = 2, topology version, step, N, P, 0; f64 simulated time;
//             P x 6 f32   each piece's box: min[3], step[3]
//             N x 3 u16   node positions, quantised in their piece's box: x = min + q step
// Boxes are per piece so that a piece falling away does not coarsen the others' positions.
// The page places the surface's vertices from the nodes (weights times corners), so a frame is
// 6 bytes a node (16 KB for the default scene's 2.6k nodes), however fine the surface. Topology
// goes out only when a cut changed it, as the patches it changed (a blade pose changes a few
// tets' patches: tens of kilobytes, where the whole topology of the default scene is 1.9 MB), and whole
// to a page that joins or has fallen behind by more than that.
// A vertex on the border of two patches is in both: each patch stands alone, so replacing one
// never renumbers another (the page draws with flat shading, which needs no shared vertices).
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
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace tetcut::live {

inline constexpr std::uint32_t kTopologyMessage = 1;
inline constexpr std::uint32_t kFrameMessage = 2;
/// A topology's flags: which of its indices are 16-bit.
inline constexpr std::uint32_t kNarrowNodes = 1, kNarrowPatches = 2;
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

inline constexpr std::size_t kTopologyHeader = 40;

/// Encodes topology messages, remembering the last one's patches so that the next can say only
/// what changed.
class TopologyEncoder {
 public:
  /// `wide`: 32-bit indices whatever the counts (for tests).
  explicit TopologyEncoder(bool wide = false) : wide_(wide) {}

  struct Messages {
    std::uint32_t version = 0;
    std::string full;    ///< base 0: the whole topology
    std::string change;  ///< base version - 1: what changed; empty when the last encode was not of version - 1
  };
  /// The topology of a cut mesh: its copies (`copy_nodes`, as Cutter::tet_nodes) and their input
  /// tets (`tet_parent`), the pieces of its nodes, and its material surface (whose triangles come
  /// grouped by input tet in increasing order, as Cutter::surface gives them). O(T + V + F).
  Messages encode(std::uint32_t version, const std::vector<std::array<Index, 4>>& copy_nodes, std::span<const Index> tet_parent,
                  const NodePieces& pieces, const MaterialSurface& surface);
  /// The same for a session as it stands; sets `pieces`, which its frames quantise by.
  Messages encode(std::uint32_t version, Session& session, NodePieces* pieces);

 private:
  bool wide_;
  std::uint32_t last_version_ = 0;
  // The patches as encoded last, one after another: tet t's is bytes_[offsets_[t], offsets_[t + 1])
  // (empty: none).
  std::string bytes_, next_bytes_;
  std::vector<std::size_t> offsets_, next_offsets_;
  std::vector<std::int32_t> local_;   // per surface vertex: its index in the patch being encoded
};

/// A frame message: node positions quantised to 16 bits in their piece's bounding box.
std::string encode_frame(std::uint32_t version, std::uint32_t step, double time, const Points& nodes, const NodePieces& pieces);

/// The JSON of an error reply.
std::string error_message(std::string_view message, std::optional<std::int64_t> seq);

}  // namespace tetcut::live
