// The paper's lip case (Figure 10): two parts of a closed surface come closer than one tet of the
// coarse mesh, like an upper and a lower lip. Embedding gives each part its own copies of the tets
// they share, so the mouth can open: here the lower lip is pulled down and the upper one lifted,
// and the material surface follows its copies. Then an incision cuts the upper lip, on the same
// cutter. Run it with an output directory: lips out/
//
// Open lips_closed.obj and lips_open.obj (or the .vtu meshes, coloured by piece) in ParaView or
// Blender.

#include <tetcut/embed.hpp>
#include <tetcut/figures.hpp>
#include <tetcut/io.hpp>
#include <tetcut/render.hpp>

#include <cstdio>
#include <filesystem>

int main(int argc, char** argv) {
  const std::filesystem::path out = argc > 1 ? argv[1] : ".";
  std::filesystem::create_directories(out);
  using tetcut::Box;
  using tetcut::Vec3;

  // Two slabs 0.39 thick with a gap of 0.02 between them, in a lattice of cube size 0.25.
  const tetcut::TriangleSurface lips =
      tetcut::figures::concatenate(tetcut::figures::box_surface(Box{Vec3(0, 0, 0.01), Vec3(1, 1, 0.4)}),
                                   tetcut::figures::box_surface(Box{Vec3(0, 0, -0.4), Vec3(1, 1, -0.01)}));
  tetcut::EmbedReport report;
  tetcut::Cutter cutter = tetcut::embed(tetcut::embedding_lattice(lips, 0.25), lips, {}, &report);
  tetcut::CutResult result = cutter.result();
  std::printf("lattice of %d tets: %d hold material, %d of them hold both lips and were duplicated\n", report.tets_in,
              report.tets_with_material, report.tets_duplicated);
  std::printf("%d tet copies, %d pieces of volume %.6f and %.6f\n", result.mesh.mesh.num_tets(), result.mesh.num_pieces(),
              result.mesh.piece_volumes[0], result.mesh.piece_volumes[1]);
  tetcut::write_surface(out / "lips_closed.obj", result.surface.surface);
  tetcut::TetMeshWriteOptions options;
  options.tet_labels = result.mesh.tet_piece;
  tetcut::write_tet_mesh(out / "lips_closed.vtu", result.mesh.mesh, options);

  // Open the mouth: each piece moves by itself (a rigid offset stands in for a simulation here).
  // Piece 0 and 1 have equal volume; tell them apart by where their material is.
  tetcut::Points moved = result.mesh.mesh.rest();
  const tetcut::Points rest_surface = result.surface.surface.vertices;
  std::vector<double> lift(2, 0);
  for (tetcut::Index v = 0; v < result.surface.surface.num_vertices(); ++v) {
    lift[result.mesh.tet_piece[result.surface.vertex_tet[v]]] += rest_surface(v, 2);
  }
  for (tetcut::Index c = 0; c < result.mesh.mesh.num_tets(); ++c) {
    const int piece = result.mesh.tet_piece[c];
    const double dz = lift[piece] > 0 ? 0.3 : -0.3;
    for (int k = 0; k < 4; ++k) moved(result.mesh.mesh.tets()(c, k), 2) = result.mesh.mesh.rest()(result.mesh.mesh.tets()(c, k), 2) + dz;
  }
  tetcut::TriangleSurface open = result.surface.surface;
  open.vertices = result.surface.positions(result.mesh, moved);
  tetcut::write_surface(out / "lips_open.obj", open);
  // The open mouth, with the edges of the tet copies each lip took along.
  tetcut::render::RenderOptions picture;
  picture.line_points = moved;
  picture.lines = tetcut::render::mesh_edges(result.mesh.mesh);
  tetcut::render::write_png(out / "lips_open.png", tetcut::render::render(open, picture));

  // An incision through the upper lip, on the same cutter: a vertical cut x = 0.5 reaching from
  // above down to halfway into the lip.
  tetcut::TriangleSurface incision;
  incision.vertices.resize(4, 3);
  incision.vertices << 0.5, -0.5, 0.2, 0.5, 1.5, 0.2, 0.5, 1.5, 1.0, 0.5, -0.5, 1.0;
  incision.triangles.resize(2, 3);
  incision.triangles << 0, 1, 2, 0, 2, 3;
  const tetcut::CutBatchReport batch = cutter.cut(incision);
  result = cutter.result();
  std::printf("incision: %d tets touched, now %d tet copies, %d pieces\n", batch.tets_touched, result.mesh.mesh.num_tets(),
              result.mesh.num_pieces());
  tetcut::write_surface(out / "lips_incised.obj", result.surface.surface);
  tetcut::render::write_png(out / "lips_incised.png", tetcut::render::render(result.surface.surface));
  std::printf("wrote lips_closed.obj, lips_closed.vtu, lips_open.obj and lips_incised.obj in %s, with pictures lips_open.png "
              "and lips_incised.png\n",
              out.string().c_str());
  return 0;
}
