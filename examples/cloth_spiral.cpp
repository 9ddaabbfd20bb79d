// The paper's Figure 1: the two-dimensional version of the algorithm. A square of cloth made of
// 128 triangles hangs from its top edge and is cut, progressively while it hangs, along a spiral
// from its edge in to its centre; the cloth unwinds into a long ribbon. Every triangle the spiral
// crosses gets one copy per strip of material it holds, so the coarse mesh stays 128 triangles
// of full size while the ribbon's shape is exact.
//
// Run: example_cloth_spiral OUT [FRAMES] [SPACING]
//   FRAMES: 600 (ten seconds at 60 a second; CTest runs 20); SPACING: between the spiral's turns,
//   0.08 m (a ribbon about 9 m long; at 0.028 the spiral makes about as many copies as the paper's).
// Writes cloth_spiral.png (the last frame), cloth_spiral_frames/ and cloth_spiral.gif (when ffmpeg
// is installed), and cloth_spiral.obj (the material at the end).

#include <tetcut/cloth.hpp>
#include <tetcut/cutting_surfaces.hpp>
#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>
#include <tetcut/planar_cutter.hpp>
#include <tetcut/render.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

namespace {

using tetcut::Index;

// The cut: in through the middle of the bottom edge, then the spiral r = r0 - spacing * a / (2 pi)
// about the square's centre (a the angle turned, clockwise from straight down) in to radius
// `spacing`, as points about `step` apart. With r0 below half the side the spiral stays inside
// the square, so the material is one ribbon.
tetcut::Points2 spiral_cut(double spacing, double step) {
  const tetcut::Points2 turns = tetcut::spiral(Eigen::Vector2d(0.5, 0.5), 0.48, spacing, spacing, step);
  tetcut::Points2 out(turns.rows() + 1, 2);
  out.row(0) << 0.5, -0.05;
  out.bottomRows(turns.rows()) = turns;
  return out;
}

tetcut::TriangleSurface material_surface(const tetcut::PlanarCutResult& cut, const tetcut::Points& nodes) {
  tetcut::TriangleSurface surface;
  surface.vertices = cut.material.positions(cut.mesh, nodes);
  surface.triangles = cut.material.triangles;
  return surface;
}

}  // namespace

int main(int argc, char** argv) {
  const std::filesystem::path out = argc > 1 ? argv[1] : ".";
  const int frames = argc > 2 ? std::atoi(argv[2]) : 600;
  const double spacing = argc > 3 ? std::atof(argv[3]) : 0.08;
  if (frames < 1 || !(spacing > 0.005 && spacing < 0.4)) {
    std::fprintf(stderr, "usage: example_cloth_spiral OUT [FRAMES >= 1] [SPACING in (0.005, 0.4)]\n");
    return 2;
  }
  std::filesystem::create_directories(out / "cloth_spiral_frames");

  // 8 x 8 cells, each two triangles: 128 triangles on a metre square.
  const int n = 8;
  const tetcut::PlanarMesh square = tetcut::make_planar_grid(n);
  tetcut::PlanarCutter cutter(square);
  tetcut::PlanarCutResult cut = cutter.result();

  // Hung in the x-z plane: rest (u, v) at (u, 0, v), pinned along the top edge v = 1.
  tetcut::Points hanging(square.num_nodes(), 3);
  for (Index i = 0; i < square.num_nodes(); ++i) hanging.row(i) << square.rest(i, 0), 0, square.rest(i, 1);
  tetcut::sim::ClothMaterial material;
  material.stretch_stiffness = 2000;
  material.bending_stiffness = 1e-4;
  material.mass_damping = 0.5;
  tetcut::sim::ClothSimulator cloth(cut.mesh, hanging, material);
  for (int i = 0; i <= n; ++i) cloth.pin(n * (n + 1) + i);

  // The spiral, cut a stretch per frame over the first two thirds of the run, then let hang.
  const tetcut::Points2 path = spiral_cut(spacing, 0.01);
  const Index segments = static_cast<Index>(path.rows()) - 1;
  const int cutting_frames = std::max(1, 2 * frames / 3);
  const Index per_frame = (segments + cutting_frames - 1) / cutting_frames;
  Index done = 0;
  tetcut::sim::ClothStepOptions options;
  options.dt = 1.0 / 60;
  double step_ms = 0, cut_ms = 0;
  int converged = 0;
  tetcut::render::RenderOptions picture;
  picture.width = 450;
  picture.height = 900;
  picture.camera.azimuth_degrees = -90;  // looking along +y at the x-z plane
  picture.camera.elevation_degrees = 10;
  picture.camera.zoom = 1.5;
  picture.frame = Eigen::AlignedBox3d(tetcut::Vec3(-0.6, -0.5, -3.4), tetcut::Vec3(1.6, 0.5, 1.1));
  for (int frame = 0; frame < frames; ++frame) {
    if (done < segments) {
      const Index count = std::min(per_frame, segments - done);
      tetcut::Polyline stretch;
      stretch.points = path.middleRows(done, count + 1);
      const auto start = std::chrono::steady_clock::now();
      const tetcut::PlanarCutReport report = cutter.cut(std::span<const tetcut::Polyline>(&stretch, 1));
      cut = cutter.result();
      cloth.remesh(cut.mesh, report);
      cut_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      done += count;
    }
    const tetcut::sim::ClothStepReport step = cloth.step(options);
    step_ms += 1e3 * step.seconds;
    converged += step.converged ? 1 : 0;
    if (frame % 4 == 0 || frame + 1 == frames) {
      char name[64];
      std::snprintf(name, sizeof name, "frame_%04d.png", frame / 4);
      // The material, and over it the edges of the triangle copies it is embedded in.
      picture.line_points = cloth.positions();
      picture.lines = tetcut::triangle_edges(cut.mesh.mesh.triangles);
      tetcut::render::write_png(out / "cloth_spiral_frames" / name,
                                tetcut::render::render(material_surface(cut, cloth.positions()), picture));
    }
  }
  std::printf("%d frames: %lld of %lld spiral segments cut; %d triangle copies (the paper: 587) from 128 triangles, %d nodes, "
              "%d pieces\n",
              frames, static_cast<long long>(done), static_cast<long long>(segments), cut.mesh.mesh.num_triangles(),
              cut.mesh.mesh.num_nodes(), cut.mesh.num_pieces());
  std::printf("cloth step %.2f ms, cut + remesh %.2f ms a frame on average; %d of %d steps converged\n", step_ms / frames,
              cut_ms / frames, converged, frames);
  const tetcut::TriangleSurface last = material_surface(cut, cloth.positions());
  tetcut::write_surface(out / "cloth_spiral.obj", last);
  picture.line_points = cloth.positions();
  picture.lines = tetcut::triangle_edges(cut.mesh.mesh.triangles);
  tetcut::render::write_png(out / "cloth_spiral.png", tetcut::render::render(last, picture));
  try {
    tetcut::render::write_animation(out / "cloth_spiral_frames" / "frame_%04d.png", 15, out / "cloth_spiral.gif");
    std::printf("wrote cloth_spiral.png, cloth_spiral.gif and cloth_spiral.obj in %s\n", out.string().c_str());
  } catch (const tetcut::Error& e) {
    std::printf("wrote cloth_spiral.png and cloth_spiral.obj in %s; no animation: %s\n", out.string().c_str(), e.what());
  }
  return 0;
}
