// The library in a few lines: cut a cube of tets by two planes, look at the pieces, and move the
// material surface with the mesh. Run it with an output directory: cut_a_cube out/
//
// A simulator would keep the Cutter, feed it batches of cut triangles as they happen, and after
// each batch take the new mesh (node_parent says which old node each new node copies, so positions
// and velocities carry over) and the surface (which follows the nodes through its weights).

#include <tetcut/cutter.hpp>
#include <tetcut/figures.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>
#include <tetcut/render.hpp>

#include <cstdio>
#include <filesystem>

int main(int argc, char** argv) {
  const std::filesystem::path out = argc > 1 ? argv[1] : ".";
  std::filesystem::create_directories(out);

  // A 3 x 3 x 3 grid of 6-tet cubes over the unit cube, cut by x = 0.4, then by y = 0.7.
  const tetcut::TetMesh cube = tetcut::make_grid(tetcut::Box{}, {3, 3, 3}, 6);
  tetcut::Cutter cutter(cube);
  cutter.cut(tetcut::figures::axis_square(0, 0.4, -1, 2));
  cutter.cut(tetcut::figures::axis_square(1, 0.7, -1, 2));
  const tetcut::CutResult result = cutter.result();

  std::printf("%d tets became %d tet copies over %d nodes (was %d)\n", cube.num_tets(), result.mesh.mesh.num_tets(),
              result.mesh.mesh.num_nodes(), cube.num_nodes());
  for (tetcut::Index p = 0; p < result.mesh.num_pieces(); ++p) {
    std::printf("  piece %d: volume %.6f\n", p, result.mesh.piece_volumes[p]);
  }

  // Deform the cut mesh (here: pull each piece away from the centre) and move the surface with it.
  tetcut::Points moved = result.mesh.mesh.rest();
  for (tetcut::Index c = 0; c < result.mesh.mesh.num_tets(); ++c) {
    const int piece = result.mesh.tet_piece[c];
    const tetcut::Vec3 push(piece % 2 == 0 ? 0.1 : -0.1, piece < 2 ? 0.1 : -0.1, 0);
    for (int k = 0; k < 4; ++k) moved.row(result.mesh.mesh.tets()(c, k)) = result.mesh.mesh.rest().row(result.mesh.mesh.tets()(c, k)) + push.transpose();
  }
  tetcut::TriangleSurface surface = result.surface.surface;
  surface.vertices = result.surface.positions(result.mesh, moved);
  tetcut::write_surface(out / "cube_pieces_apart.obj", surface);
  // A picture: each piece in its own colour (offscreen OpenGL ES; no display or GPU needed).
  tetcut::render::write_png(out / "cube_pieces_apart.png", tetcut::render::render(surface));
  std::printf("wrote %s and its picture, cube_pieces_apart.png\n", (out / "cube_pieces_apart.obj").string().c_str());
  return 0;
}
