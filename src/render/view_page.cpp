// The viewer page: the HTML template and the bundled three.js script (both compiled in, see
// viewer_assets.hpp) with the frames inlined as JSON whose arrays are base64 of little-endian
// uint16 / uint32 / uint8 data, which the page turns into typed arrays without parsing numbers.
// Positions are quantised to 16 bits per coordinate within their frame's bounding box (a step of
// 1/65535 of the box, far below a pixel), which halves the page against float32.

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>
#include <tetcut/render.hpp>
#include <tetcut/tet_mesh.hpp>
#include <tetcut/view.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string_view>

#include "io/binary.hpp"
#include "render/viewer_assets.hpp"

namespace tetcut::view {
namespace {

static_assert(std::endian::native == std::endian::little, "the page's typed arrays are little-endian");

template <typename T, typename Matrix>
std::string base64_of(const Matrix& matrix) {
  std::string bytes(static_cast<std::size_t>(matrix.size()) * sizeof(T), '\0');
  char* out = bytes.data();
  for (Eigen::Index r = 0; r < matrix.rows(); ++r) {
    for (Eigen::Index c = 0; c < matrix.cols(); ++c, out += sizeof(T)) {
      const T value = static_cast<T>(matrix(r, c));
      std::memcpy(out, &value, sizeof(T));
    }
  }
  return io::base64_encode(bytes);
}

// Positions as {"min": [x, y, z], "step": [dx, dy, dz], "q": base64 of uint16 x 3 per point}:
// point = min + q * step, with the rounding error at most half a step.
nlohmann::json quantised(const Points& points) {
  Vec3 low = Vec3::Zero(), high = Vec3::Zero();
  if (points.rows() > 0) {
    low = points.colwise().minCoeff().transpose();
    high = points.colwise().maxCoeff().transpose();
  }
  // A flat or empty axis has no extent to divide: any positive step quantises it to 0.
  constexpr double kFlatStep = 1e-300;
  const Vec3 step = ((high - low) / 65535.0).cwiseMax(Vec3::Constant(kFlatStep));
  Eigen::Matrix<std::uint16_t, Eigen::Dynamic, 3, Eigen::RowMajor> q(points.rows(), 3);
  for (Index v = 0; v < points.rows(); ++v) {
    for (int c = 0; c < 3; ++c) {
      q(v, c) = static_cast<std::uint16_t>(std::clamp(std::lround((points(v, c) - low[c]) / step[c]), 0L, 65535L));
    }
  }
  return {{"min", {low[0], low[1], low[2]}}, {"step", {step[0], step[1], step[2]}}, {"q", base64_of<std::uint16_t>(q)}};
}

// RGB per vertex: the colour of its piece (pieces are connected through shared vertices, so a
// vertex has one), grey for a vertex no triangle uses.
Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 3, Eigen::RowMajor> vertex_colours(const TriangleSurface& surface, Index* pieces) {
  Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 3, Eigen::RowMajor> colours(surface.num_vertices(), 3);
  colours.setConstant(200);
  const std::vector<Index> piece = render::surface_pieces(surface);
  *pieces = 0;
  for (Index t = 0; t < surface.num_triangles(); ++t) {
    const auto rgb = render::piece_colour(piece[t]);
    *pieces = std::max(*pieces, piece[t] + 1);
    for (int k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c) colours(surface.triangles(t, k), c) = rgb[c];
    }
  }
  return colours;
}

std::string html_escaped(std::string_view text) {
  std::string out;
  for (const char c : text) {
    if (c == '&') out += "&amp;";
    else if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

// JSON inside <script> must not close the element: "</" becomes the equivalent "<\/".
std::string script_safe(std::string_view json) {
  std::string out;
  out.reserve(json.size());
  for (std::size_t i = 0; i < json.size(); ++i) {
    out += json[i];
    if (json[i] == '<' && i + 1 < json.size() && json[i + 1] == '/') out += '\\';
  }
  return out;
}

}  // namespace

bool available() { return !kViewerScript.empty(); }

std::string page(const std::string& title, const std::vector<ViewFrame>& frames) {
  if (!available()) {
    throw Error(ErrorKind::kUnsupported,
                "this tetcut was built without the web viewer (Node.js and npm were missing; run scripts/install-deps.sh "
                "and rebuild)");
  }
  if (frames.empty()) throw Error(ErrorKind::kInvalidArgument, "the viewer needs at least one frame");
  nlohmann::json data;
  data["title"] = title;
  const bool triangles = std::any_of(frames.begin(), frames.end(), [](const ViewFrame& f) { return f.mesh_triangles; });
  data["mesh_kind"] = triangles ? "triangles" : "tets";
  nlohmann::json& out_frames = data["frames"];
  out_frames = nlohmann::json::array();
  const ViewFrame* previous = nullptr;
  Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 3, Eigen::RowMajor> colours;
  Index pieces = 0;
  for (const ViewFrame& frame : frames) {
    const TriangleSurface& surface = frame.surface;
    nlohmann::json f;
    f["time"] = std::isfinite(frame.time) ? nlohmann::json(frame.time) : nlohmann::json(nullptr);
    const bool same_triangles = previous && previous->surface.triangles.rows() == surface.triangles.rows() &&
                                previous->surface.triangles == surface.triangles;
    // Pieces and their colours follow from the triangles alone: found again only when they change.
    const bool same_colours = same_triangles && previous->surface.num_vertices() == surface.num_vertices();
    if (!same_colours) colours = vertex_colours(surface, &pieces);
    f["surface"] = {
        {"positions", quantised(surface.vertices)},
        {"triangles", same_triangles ? nlohmann::json(nullptr) : nlohmann::json(base64_of<std::uint32_t>(surface.triangles))},
        {"colours", same_colours ? nlohmann::json(nullptr) : nlohmann::json(base64_of<std::uint8_t>(colours))},
        {"pieces", pieces},
    };
    if (frame.mesh_edges.rows() > 0) {
      // Edges are shared only with a frame that has edges itself.
      const bool same_edges = previous && previous->mesh_edges.rows() == frame.mesh_edges.rows() &&
                              previous->mesh_edges == frame.mesh_edges;
      f["mesh"] = {
          {"positions", quantised(frame.mesh_points)},
          {"edges", same_edges ? nlohmann::json(nullptr) : nlohmann::json(base64_of<std::uint32_t>(frame.mesh_edges))},
      };
    } else {
      f["mesh"] = nullptr;
    }
    out_frames.push_back(std::move(f));
    previous = &frame;
  }

  // Fill the template's three slots in one pass, so nothing inserted is scanned again.
  const std::string_view tmpl = kViewerPage;
  const std::string json = script_safe(data.dump());
  std::string html;
  html.reserve(tmpl.size() + json.size() + kViewerScript.size() + title.size());
  std::size_t at = 0;
  for (std::size_t open = tmpl.find("{{"); open != std::string_view::npos; open = tmpl.find("{{", at)) {
    const std::size_t close = tmpl.find("}}", open);
    if (close == std::string_view::npos) break;
    const std::string_view slot = tmpl.substr(open + 2, close - open - 2);
    html.append(tmpl.substr(at, open - at));
    if (slot == "TITLE") html += html_escaped(title);
    else if (slot == "DATA") html += json;
    else if (slot == "SCRIPT") html.append(kViewerScript);
    else html.append(tmpl.substr(open, close + 2 - open));
    at = close + 2;
  }
  html.append(tmpl.substr(at));
  return html;
}

void write_page(const std::filesystem::path& path, const std::string& title, const std::vector<ViewFrame>& frames) {
  write_text_file(path, page(title, frames));
}

namespace {

ViewFrame mesh_frame(const TetMesh& mesh) {
  ViewFrame frame;
  frame.surface = boundary_surface(mesh);
  frame.mesh_points = mesh.rest();
  frame.mesh_edges = render::mesh_edges(mesh);
  return frame;
}

// The edges of a mesh file to show over a surface: a tet mesh's, or a triangle surface's (a cloth's
// triangle copies, as 'tetcut sim' and 'tetcut cut2d --copies' write them).
ViewFrame edges_frame(const std::filesystem::path& path) {
  if (file_kind(path) == FileKind::kTetMesh) return mesh_frame(read_tet_mesh(path));
  ViewFrame frame;
  const TriangleSurface copies = read_surface(path);
  frame.mesh_points = copies.vertices;
  frame.mesh_edges = triangle_edges(copies.triangles);
  frame.mesh_triangles = true;
  return frame;
}

}  // namespace

std::vector<ViewFrame> load_frames(const std::filesystem::path& input, const std::filesystem::path& mesh) {
  std::vector<ViewFrame> frames;
  if (std::filesystem::is_directory(input)) {
    const std::filesystem::path surfaces = input / "surface.pvd", meshes = input / "mesh.pvd";
    if (!std::filesystem::exists(surfaces)) {
      throw Error(ErrorKind::kInvalidInput,
                  "no surface.pvd here: a directory to view is one that 'tetcut sim' wrote (or give a surface or mesh file)",
                  input.string());
    }
    const std::vector<SeriesEntry> surface_series = read_series(surfaces);
    std::vector<SeriesEntry> mesh_series;
    if (std::filesystem::exists(meshes)) {
      mesh_series = read_series(meshes);
      if (mesh_series.size() != surface_series.size()) {
        throw Error(ErrorKind::kInvalidInput,
                    "mesh.pvd lists " + std::to_string(mesh_series.size()) + " frames but surface.pvd lists " +
                        std::to_string(surface_series.size()),
                    meshes.string());
      }
    }
    Tets previous_tets;
    Triangles previous_copies;
    for (std::size_t f = 0; f < surface_series.size(); ++f) {
      ViewFrame frame;
      frame.time = surface_series[f].time;
      frame.surface = read_surface(surface_series[f].file);
      if (!mesh_series.empty() && file_kind(mesh_series[f].file) == FileKind::kSurface) {
        // A cloth scene's frame: its triangle copies, where they are.
        const TriangleSurface copies = read_surface(mesh_series[f].file);
        frame.mesh_points = copies.vertices;
        const bool same = f > 0 && previous_copies.rows() == copies.triangles.rows() && previous_copies == copies.triangles;
        frame.mesh_edges = same ? frames.back().mesh_edges : triangle_edges(copies.triangles);
        frame.mesh_triangles = true;
        previous_copies = copies.triangles;
      } else if (!mesh_series.empty()) {
        const TetMesh tets = read_tet_mesh(mesh_series[f].file);
        frame.mesh_points = tets.rest();  // a sim frame's mesh file holds its current positions
        // The edges (an adjacency build) change only when a cut changes the tets.
        const bool same_tets = f > 0 && previous_tets.rows() == tets.tets().rows() && previous_tets == tets.tets();
        frame.mesh_edges = same_tets ? frames.back().mesh_edges : render::mesh_edges(tets);
        previous_tets = tets.tets();
      }
      frames.push_back(std::move(frame));
    }
  } else if (file_kind(input) == FileKind::kTetMesh) {
    frames.push_back(mesh_frame(read_tet_mesh(input)));
  } else {
    ViewFrame frame;
    frame.surface = read_surface(input);
    frames.push_back(std::move(frame));
  }
  if (!mesh.empty()) {
    const ViewFrame edges = edges_frame(mesh);
    for (ViewFrame& frame : frames) {
      frame.mesh_points = edges.mesh_points;
      frame.mesh_edges = edges.mesh_edges;
      frame.mesh_triangles = edges.mesh_triangles;
    }
  }
  return frames;
}

}  // namespace tetcut::view
