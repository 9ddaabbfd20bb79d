// tetcut_fuzz: seeded, structured fuzzing of the file readers and of the cutter, bounded in time.
//
//   tetcut_fuzz readers SECONDS SEED SAVE_DIR   mutate valid files of every format (flipped bytes,
//                                               truncation, junk tokens, lines deleted or repeated)
//                                               and read them: a read must succeed with a valid
//                                               mesh or throw tetcut::Error naming the file
//   tetcut_fuzz soups SECONDS SEED SAVE_DIR     random and degenerate soups (through nodes, along
//                                               faces, coplanar repeats, tiny, partial) cut into
//                                               small grids: the cut invariants hold, and the
//                                               pieces do not depend on triangle order or batching
//   tetcut_fuzz replay DIR                      every file kept in DIR (tests/data/regressions) read
//                                               again, or re-cut when it is a saved soup
//
// An input that breaks a rule is written to SAVE_DIR (to be kept under tests/data/regressions as a
// regression test) and the run fails. A seed gives the same inputs every time.

#include <tetcut/cutter.hpp>
#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "support/cut_invariants.hpp"

namespace fs = std::filesystem;
using namespace tetcut;
using Clock = std::chrono::steady_clock;

namespace {

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void write_bytes(const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }

// Reads `path` by its kind. Returns "" when the read succeeded or refused it properly, else what
// went wrong.
std::string try_read(const fs::path& path) {
  try {
    if (file_kind(path) == FileKind::kTetMesh) {
      const TetMesh mesh = read_tet_mesh(path);  // TetMesh validates ids, finiteness, volumes
      (void)mesh;
    } else {
      const TriangleSurface s = read_surface(path);
      for (Index t = 0; t < s.num_triangles(); ++t) {
        for (int k = 0; k < 3; ++k) {
          if (s.triangles(t, k) < 0 || s.triangles(t, k) >= s.num_vertices()) return "a triangle names a vertex that does not exist";
        }
      }
    }
    return "";
  } catch (const Error& e) {
    if (e.kind() == ErrorKind::kInternal) return std::string("an internal error (a bug): ") + e.what();
    if (std::string(e.what()).empty()) return "an error without a message";
    if (e.file().empty()) return std::string("an error that names no file: ") + e.what();
    return "";
  } catch (const std::exception& e) {
    return std::string("not a tetcut::Error: ") + e.what();
  }
}

// Valid files of every format, written by our writers.
std::vector<fs::path> samples(const fs::path& dir) {
  const TetMesh mesh = make_bcc(Box{}, 0.5);
  Cutter cutter{TetMesh(mesh)};
  const TriangleSurface surface = cutter.surface().surface;
  std::vector<fs::path> out;
  for (const char* name : {"m.mesh", "m.msh", "m.vtu", "m.vtk", "m.node"}) {
    write_tet_mesh(dir / name, mesh);
    out.push_back(dir / name);
  }
  TetMeshWriteOptions gmsh22;
  gmsh22.gmsh_version = 22;
  write_tet_mesh(dir / "m22.msh", mesh, gmsh22);
  out.push_back(dir / "m22.msh");
  out.push_back(dir / "m.ele");
  for (const char* name : {"s.obj", "s.off", "s.ply", "s.stl", "s.vtp"}) {
    write_surface(dir / name, surface);
    out.push_back(dir / name);
  }
  for (const char* name : {"b.ply", "b.stl"}) {
    write_surface(dir / name, surface, SurfaceWriteOptions{true});
    out.push_back(dir / name);
  }
  return out;
}

std::string mutate(std::string bytes, std::mt19937_64& random) {
  const auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n == 0 ? 0 : n - 1)(random); };
  static const char* junk[] = {"nan", "-1", "1e999", "999999999", "-999999999", "0", "inf", "x", "", "\n", "4294967296", "2147483647"};
  const int edits = 1 + static_cast<int>(pick(4));
  for (int e = 0; e < edits && !bytes.empty(); ++e) {
    switch (pick(6)) {
      case 0:  // flip a byte
        bytes[pick(bytes.size())] = static_cast<char>(pick(256));
        break;
      case 1:  // truncate
        bytes.resize(pick(bytes.size()));
        break;
      case 2: {  // replace a token with junk
        const std::size_t at = pick(bytes.size());
        const std::size_t end = std::min(bytes.size(), bytes.find_first_of(" \n\t\"<>", at));
        bytes.replace(at, end - at, junk[pick(std::size(junk))]);
        break;
      }
      case 3: {  // delete a line
        const std::size_t at = bytes.rfind('\n', pick(bytes.size()));
        const std::size_t start = at == std::string::npos ? 0 : at + 1;
        const std::size_t end = bytes.find('\n', start);
        bytes.erase(start, end == std::string::npos ? std::string::npos : end - start + 1);
        break;
      }
      case 4: {  // repeat a line
        const std::size_t at = bytes.rfind('\n', pick(bytes.size()));
        const std::size_t start = at == std::string::npos ? 0 : at + 1;
        const std::size_t end = bytes.find('\n', start);
        bytes.insert(start, bytes.substr(start, end == std::string::npos ? std::string::npos : end - start + 1));
        break;
      }
      default:  // insert random bytes
        bytes.insert(pick(bytes.size()), std::string(1 + pick(8), static_cast<char>(pick(256))));
    }
  }
  return bytes;
}

int fuzz_readers(double seconds, std::uint64_t seed, const fs::path& save) {
  const fs::path dir = fs::temp_directory_path() / ("tetcut_fuzz_" + std::to_string(seed) + "_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::vector<fs::path> files = samples(dir);
  std::mt19937_64 random(seed);
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  long runs = 0;
  int failures = 0;
  std::vector<std::string> originals;
  for (const fs::path& f : files) originals.push_back(read_bytes(f));
  while (Clock::now() < end) {
    const std::size_t which = std::uniform_int_distribution<std::size_t>(0, files.size() - 1)(random);
    const fs::path& target = files[which];
    // .node and .ele are read as a pair: mutate one of them.
    const std::string mutated = mutate(originals[which], random);
    write_bytes(target, mutated);
    const std::string problem = try_read(target);
    write_bytes(target, originals[which]);
    ++runs;
    if (!problem.empty()) {
      ++failures;
      fs::create_directories(save);
      const fs::path kept = save / ("reader_" + std::to_string(seed) + "_" + std::to_string(runs) + target.extension().string());
      write_bytes(kept, mutated);
      std::printf("FAIL %s: %s (kept as %s)\n", target.filename().c_str(), problem.c_str(), kept.c_str());
      if (failures >= 5) break;
    }
  }
  fs::remove_all(dir);
  std::printf("readers: %ld mutated files read in %.0f s (seed %llu), %d failure(s)\n", runs, seconds,
              static_cast<unsigned long long>(seed), failures);
  return failures == 0 ? 0 : 1;
}

// A soup on a grid of `cells` cubes over the unit box, of several kinds.
TriangleSurface random_soup(std::mt19937_64& random, int cells) {
  std::uniform_real_distribution<double> unit(-0.2, 1.2);
  std::uniform_int_distribution<int> node(0, cells);
  std::uniform_int_distribution<int> kind(0, 5);
  std::vector<testing::Triangle> triangles;
  const int count = std::uniform_int_distribution<int>(1, 10)(random);
  // Components drawn one by one, in order (a seed gives the same soup on every compiler).
  const auto grid_point = [&] {
    Vec3 p;
    for (int c = 0; c < 3; ++c) p[c] = static_cast<double>(node(random)) / cells;
    return p;
  };
  const auto any_point = [&] {
    Vec3 p;
    for (int c = 0; c < 3; ++c) p[c] = unit(random);
    return p;
  };
  for (int i = 0; i < count; ++i) {
    switch (kind(random)) {
      case 0:  // anywhere
        triangles.push_back({any_point(), any_point(), any_point()});
        break;
      case 1:  // through grid nodes
        triangles.push_back({grid_point(), grid_point(), grid_point()});
        break;
      case 2: {  // along a grid plane, reaching past the box
        const int axis = std::uniform_int_distribution<int>(0, 2)(random);
        const double at = static_cast<double>(node(random)) / cells;
        std::array<Vec3, 3> t;
        for (Vec3& p : t) {
          p = any_point();
          p[axis] = at;
        }
        triangles.push_back(t);
        break;
      }
      case 3:  // a repeat of one before, corners rotated (coplanar, overlapping)
        if (!triangles.empty()) {
          const testing::Triangle t = triangles[std::uniform_int_distribution<std::size_t>(0, triangles.size() - 1)(random)];
          triangles.push_back({t[1], t[2], t[0]});
        }
        break;
      case 4: {  // tiny, inside one tet
        const Vec3 c = any_point();
        triangles.push_back({c, c + Vec3(1e-3, 0, 0), c + Vec3(0, 1e-3, 2e-4)});
        break;
      }
      default: {  // a big square's half through the middle
        const Vec3 c = grid_point(), n = any_point().normalized();
        const Vec3 u = n.unitOrthogonal(), v = n.cross(u);
        triangles.push_back({c - 2 * u - 2 * v, c + 2 * u - 2 * v, c + 2 * u + 2 * v});
      }
    }
  }
  return testing::soup(triangles);
}

std::vector<double> sorted_volumes(const CutResult& r) {
  std::vector<double> v = r.mesh.piece_volumes;
  std::sort(v.begin(), v.end());
  return v;
}

// Cuts `soup` into the grid at once, then shuffled in batches: "" when the invariants hold and
// the two agree.
std::string check_soup(const TriangleSurface& soup, int cells, int tets_per_cube, std::mt19937_64& random) {
  const TetMesh mesh = make_grid(Box{}, {cells, cells, cells}, tets_per_cube);
  Cutter at_once{TetMesh(mesh)};
  at_once.cut(soup);
  const CutResult a = at_once.result();
  std::string problem = testing::check_cut_invariants(mesh, a);
  if (!problem.empty()) return "at once: " + problem;
  std::vector<Index> order(static_cast<std::size_t>(soup.num_triangles()));
  for (Index i = 0; i < soup.num_triangles(); ++i) order[static_cast<std::size_t>(i)] = i;
  std::shuffle(order.begin(), order.end(), random);
  Cutter batched{TetMesh(mesh)};
  for (std::size_t first = 0; first < order.size();) {
    const std::size_t count = std::uniform_int_distribution<std::size_t>(1, order.size() - first)(random);
    TriangleSurface batch;
    batch.vertices = soup.vertices;
    batch.triangles.resize(static_cast<Index>(count), 3);
    for (std::size_t i = 0; i < count; ++i) batch.triangles.row(static_cast<Index>(i)) = soup.triangles.row(order[first + i]);
    batched.cut(batch);
    first += count;
  }
  const CutResult b = batched.result();
  problem = testing::check_cut_invariants(mesh, b);
  if (!problem.empty()) return "shuffled in batches: " + problem;
  const std::vector<double> va = sorted_volumes(a), vb = sorted_volumes(b);
  if (va.size() != vb.size()) return "at once " + std::to_string(va.size()) + " pieces, in batches " + std::to_string(vb.size());
  for (std::size_t i = 0; i < va.size(); ++i) {
    if (std::abs(va[i] - vb[i]) > 1e-12 * (1 + std::abs(va[i]))) return "a piece's volume depends on the order";
  }
  return "";
}

int fuzz_soups(double seconds, std::uint64_t seed, const fs::path& save) {
  std::mt19937_64 random(seed);
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  long runs = 0;
  int failures = 0;
  while (Clock::now() < end && failures < 3) {
    const int cells = std::uniform_int_distribution<int>(1, 3)(random);
    const int tets_per_cube = std::uniform_int_distribution<int>(0, 1)(random) ? 5 : 6;
    const TriangleSurface soup = random_soup(random, cells);
    const std::uint64_t check_seed = random();
    std::mt19937_64 check_random(check_seed);
    std::string problem;
    try {
      problem = check_soup(soup, cells, tets_per_cube, check_random);
    } catch (const std::exception& e) {
      problem = std::string("threw: ") + e.what();
    }
    ++runs;
    if (!problem.empty()) {
      ++failures;
      fs::create_directories(save);
      const fs::path kept = save / ("soup_" + std::to_string(seed) + "_" + std::to_string(runs) + "_" + std::to_string(cells) + "x" +
                                    std::to_string(tets_per_cube) + "_" + std::to_string(check_seed) + ".obj");
      write_surface(kept, soup);
      std::printf("FAIL soup %ld: %s (kept as %s)\n", runs, problem.c_str(), kept.c_str());
    }
  }
  std::printf("soups: %ld soups cut twice and checked in %.0f s (seed %llu), %d failure(s)\n", runs, seconds,
              static_cast<unsigned long long>(seed), failures);
  return failures == 0 ? 0 : 1;
}

// Every kept input again: readers' files are read; soups (soup_SEED_RUN_CELLSxTETS_CHECKSEED.obj)
// are re-cut and checked.
int replay(const fs::path& dir) {
  int checked = 0, failures = 0;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file() && entry.path().filename() != "README.md") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& f : files) {
    std::string problem;
    const std::string name = f.stem().string();
    if (name.rfind("soup_", 0) == 0) {
      // soup_<seed>_<run>_<cells>x<tets>_<checkseed>
      std::vector<std::string> parts;
      std::stringstream s(name);
      for (std::string p; std::getline(s, p, '_');) parts.push_back(p);
      const int cells = std::stoi(parts.at(3)), tets = std::stoi(parts.at(3).substr(parts.at(3).find('x') + 1));
      std::mt19937_64 random(std::stoull(parts.at(4)));
      try {
        problem = check_soup(read_surface(f), cells, tets, random);
      } catch (const std::exception& e) {
        problem = std::string("threw: ") + e.what();
      }
    } else {
      problem = try_read(f);
    }
    ++checked;
    if (!problem.empty()) {
      ++failures;
      std::printf("FAIL %s: %s\n", f.filename().c_str(), problem.c_str());
    }
  }
  std::printf("replay: %d kept input(s) from %s, %d failure(s)\n", checked, dir.c_str(), failures);
  return failures == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "replay" && argc == 3) return replay(argv[2]);
  if ((mode == "readers" || mode == "soups") && argc == 5) {
    const double seconds = std::atof(argv[2]);
    const std::uint64_t seed = std::strtoull(argv[3], nullptr, 10);
    return mode == "readers" ? fuzz_readers(seconds, seed, argv[4]) : fuzz_soups(seconds, seed, argv[4]);
  }
  std::fprintf(stderr, "usage: tetcut_fuzz readers|soups SECONDS SEED SAVE_DIR | tetcut_fuzz replay DIR\n");
  return 2;
}
