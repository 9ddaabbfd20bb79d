// The paper's Figures 2 and 4 through the library: cut, check the counts the paper reports, and
// write meshes and surfaces for ParaView or Blender. Run it with an output directory.

#include <tetcut/cutter.hpp>
#include <tetcut/figures.hpp>
#include <tetcut/io.hpp>
#include <tetcut/render.hpp>

#include <cstdio>
#include <filesystem>
#include <vector>

namespace {

void write(const std::filesystem::path& stem, const tetcut::CutResult& result) {
  tetcut::TetMeshWriteOptions options;
  tetcut::CellField piece{"piece", {}, true};
  for (const tetcut::Index p : result.mesh.tet_piece) piece.values.push_back(p);
  options.cell_fields.push_back(std::move(piece));
  tetcut::write_tet_mesh(stem.string() + ".vtu", result.mesh.mesh, options);
  tetcut::write_surface(stem.string() + "_surface.ply", result.surface.surface, {.binary = true});
  // The pieces touch, so pull each one away from the centre a little to see them apart.
  const tetcut::TetMesh& mesh = result.mesh.mesh;
  std::vector<tetcut::Vec3> centre_of(result.mesh.num_pieces(), tetcut::Vec3::Zero());
  std::vector<int> copies(result.mesh.num_pieces(), 0);
  tetcut::Vec3 centre = tetcut::Vec3::Zero();
  for (tetcut::Index c = 0; c < mesh.num_tets(); ++c) {
    tetcut::Vec3 middle = tetcut::Vec3::Zero();
    for (int k = 0; k < 4; ++k) middle += mesh.rest().row(mesh.tets()(c, k)).transpose() / 4;
    centre_of[result.mesh.tet_piece[c]] += middle;
    copies[result.mesh.tet_piece[c]] += 1;
    centre += middle / static_cast<double>(mesh.num_tets());
  }
  tetcut::Points apart = mesh.rest();
  for (tetcut::Index c = 0; c < mesh.num_tets(); ++c) {
    const int own = result.mesh.tet_piece[c];
    const tetcut::Vec3 push = 0.4 * (centre_of[own] / copies[own] - centre);
    for (int k = 0; k < 4; ++k) apart.row(mesh.tets()(c, k)) = mesh.rest().row(mesh.tets()(c, k)) + push.transpose();
  }
  tetcut::TriangleSurface exploded = result.surface.surface;
  exploded.vertices = result.surface.positions(result.mesh, apart);
  tetcut::render::write_png(stem.string() + ".png", tetcut::render::render(exploded));
}

}  // namespace

int main(int argc, char** argv) {
  const std::filesystem::path out = argc > 1 ? argv[1] : ".";
  std::filesystem::create_directories(out);

  tetcut::Cutter figure4(tetcut::figures::figure4_cube());
  figure4.cut(tetcut::figures::figure4_planes());
  const tetcut::CutResult sticks = figure4.result();
  std::printf("Figure 4: 32 planes cut 320 tets into %d sticks, with %d tet copies (the paper: 289 and about 8K)\n",
              sticks.mesh.num_pieces(), sticks.mesh.mesh.num_tets());
  write(out / "figure4", sticks);

  tetcut::Cutter figure2(tetcut::figures::figure2_tet());
  figure2.cut(tetcut::figures::figure2_triangles());
  const tetcut::CutResult shards = figure2.result();
  std::printf("Figure 2: 50 triangles cut one tet into %d pieces (the paper: over a thousand)\n", shards.mesh.num_pieces());
  write(out / "figure2", shards);
  return sticks.mesh.num_pieces() == 289 && shards.mesh.num_pieces() > 1000 ? 0 : 1;
}
