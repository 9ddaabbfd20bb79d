// A scalpel cutting a block while the block twists: the loop a surgical simulator runs. Each frame
// the block deforms (here by a prescribed twist, where a simulator would step its dynamics), the
// blade advances, and the blade is followed in the material: its pose is mapped to rest space
// through the current deformation, and the strip between the last two rest-space poses is cut.
// Consecutive strips share their edge exactly, so the incision is continuous even though the
// block moved between frames (see swept_blade). New nodes start where the nodes they were split
// from are. Run it with an output directory: it writes the material surface, deformed, at the end,
// and a picture of every other frame, assembled into scalpel.gif when ffmpeg is installed.

#include <tetcut/blade.hpp>
#include <tetcut/cutter.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/error.hpp>
#include <tetcut/io.hpp>
#include <tetcut/render.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <span>
#include <vector>

namespace {

// The block's deformation at time t: a twist about the vertical axis through its centre.
tetcut::Vec3 twist(const tetcut::Vec3& x, double t) {
  const double angle = 0.6 * t * x[2];
  const double u = x[0] - 0.5, v = x[1] - 0.5;
  return {0.5 + std::cos(angle) * u - std::sin(angle) * v, 0.5 + std::sin(angle) * u + std::cos(angle) * v, x[2]};
}

}  // namespace

int main(int argc, char** argv) {
  const std::filesystem::path out = argc > 1 ? argv[1] : ".";
  std::filesystem::create_directories(out);
  const tetcut::TetMesh block = tetcut::make_bcc(tetcut::Box{}, 0.125);
  tetcut::Cutter cutter(block);

  // The blade: vertical, through the whole height, crossing the block along y = 0.45 in 40 frames.
  const auto blade_at = [](double t) {
    const double x = -0.2 + 1.4 * t;
    tetcut::Points ends(2, 3);
    ends << x, 0.45, -0.2, x, 0.45, 1.2;
    return ends;
  };
  std::vector<tetcut::BladePose> in_material;
  for (int frame = 0; frame <= 40; ++frame) {
    const double t = frame / 40.0;
    // The cut mesh in its current shape: every node where the twist puts its rest position.
    tetcut::Points now(cutter.num_nodes(), 3);
    for (tetcut::Index n = 0; n < cutter.num_nodes(); ++n) {
      now.row(n) = twist(block.rest().row(cutter.node_parent()[n]).transpose(), t).transpose();
    }
    cutter.set_current(now);
    const tetcut::Points rest = cutter.to_rest(blade_at(t));
    in_material.push_back({rest.row(0).transpose(), rest.row(1).transpose()});
    if (frame > 0) {
      const tetcut::CutBatchReport report =
          cutter.cut(tetcut::swept_blade(std::span<const tetcut::BladePose>(in_material.data() + frame - 1, 2)));
      if (frame % 8 == 0) {
        std::printf("frame %2d: touched %3d tets, %3zu new nodes, %2zu new tets; mesh has %d tets\n", frame,
                    report.tets_touched, report.new_node_source.size(), report.new_tet_source.size(), cutter.num_tets());
      }
    }
    if (frame % 2 == 0) {
      // The picture of this frame: the deformed material surface and the blade, as a line.
      const tetcut::CutResult now_cut = cutter.result();
      tetcut::TriangleSurface surface = now_cut.surface.surface;
      surface.vertices = now_cut.surface.positions(now_cut.mesh, now_cut.mesh.mesh.current());
      tetcut::render::RenderOptions picture;
      picture.width = 480;
      picture.height = 360;
      picture.frame = Eigen::AlignedBox3d(tetcut::Vec3(-0.3, -0.3, -0.3), tetcut::Vec3(1.3, 1.3, 1.3));
      picture.line_points = blade_at(t);
      picture.lines.resize(1, 2);
      picture.lines << 0, 1;
      std::filesystem::create_directories(out / "scalpel_frames");
      char name[64];
      std::snprintf(name, sizeof name, "frame_%04d.png", frame / 2);
      tetcut::render::write_png(out / "scalpel_frames" / name, tetcut::render::render(surface, picture));
    }
  }
  try {
    tetcut::render::write_animation(out / "scalpel_frames" / "frame_%04d.png", 10, out / "scalpel.gif");
    std::printf("wrote scalpel.gif\n");
  } catch (const tetcut::Error& e) {
    if (e.kind() != tetcut::ErrorKind::kUnsupported) throw;
    std::printf("no animation: %s\n", e.what());  // ffmpeg is missing; the frames are there
  }
  const tetcut::CutResult result = cutter.result();
  tetcut::TriangleSurface surface = result.surface.surface;
  surface.vertices = result.surface.positions(result.mesh, result.mesh.mesh.current());
  tetcut::write_surface(out / "scalpel_twisted_block.obj", surface);
  std::printf("the blade went through: %d pieces; wrote %s\n", result.mesh.num_pieces(),
              (out / "scalpel_twisted_block.obj").string().c_str());
  return result.mesh.num_pieces() == 2 ? 0 : 1;
}
