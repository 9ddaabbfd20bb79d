// Surfaces read from inside .tar.gz archives: found by their path (also behind a ustar prefix or a
// GNU long name), the same as the unpacked file, and clear errors for a missing member or a
// damaged archive.

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "support/temp_dir.hpp"

namespace tetcut {
namespace {

using ::testing::HasSubstr;
using testing::TempDir;

const std::string kTetrahedronOff = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

// Packs dir/<members...> into dir/<archive> with the system's tar (GNU tar on Debian).
void pack(const TempDir& dir, const std::string& archive, const std::string& members) {
  const std::string command = "cd '" + dir.path().string() + "' && tar czf " + archive + " " + members;
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
}

TEST(Archive, ReadsAMemberLikeTheUnpackedFile) {
  TempDir dir;
  std::filesystem::create_directories(dir / "data/meshes");
  dir.write("data/meshes/tet.off", kTetrahedronOff);
  dir.write("data/meshes/other.off", "OFF\n0 0 0\n");
  pack(dir, "data.tar.gz", "data/meshes/other.off data/meshes/tet.off");
  const TriangleSurface packed = read_surface(dir / "data.tar.gz", "data/meshes/tet.off");
  const TriangleSurface plain = read_surface(dir / "data/meshes/tet.off");
  EXPECT_EQ(packed.vertices, plain.vertices);
  EXPECT_EQ(packed.triangles, plain.triangles);
  EXPECT_EQ(packed.num_triangles(), 4);
}

TEST(Archive, FindsMembersWithLongPaths) {
  TempDir dir;
  // Over 100 characters: GNU tar stores the name in a 'L' entry before the header.
  const std::string deep = std::string(60, 'a') + "/" + std::string(60, 'b');
  std::filesystem::create_directories(dir / deep);
  dir.write(deep + "/tet.off", kTetrahedronOff);
  pack(dir, "deep.tar.gz", deep + "/tet.off");
  EXPECT_EQ(read_surface(dir / "deep.tar.gz", deep + "/tet.off").num_triangles(), 4);
}

TEST(Archive, NamesAMissingMember) {
  TempDir dir;
  dir.write("tet.off", kTetrahedronOff);
  pack(dir, "one.tar.gz", "tet.off");
  try {
    read_surface(dir / "one.tar.gz", "bunny.off");
    FAIL() << "no error for a missing member";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInvalidInput);
    EXPECT_THAT(e.what(), HasSubstr("holds no file bunny.off"));
    EXPECT_THAT(e.file(), HasSubstr("one.tar.gz"));
  }
}

TEST(Archive, RefusesATruncatedArchive) {
  TempDir dir;
  std::string big = "OFF\n400 0 0\n";
  for (int i = 0; i < 400; ++i) big += std::to_string(i) + " " + std::to_string(i * 7 % 13) + " 0.5\n";
  dir.write("points.off", big);
  dir.write("tet.off", kTetrahedronOff);
  pack(dir, "full.tar.gz", "points.off tet.off");
  std::ifstream in(dir / "full.tar.gz", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  dir.write("cut.tar.gz", bytes.substr(0, bytes.size() / 2));
  EXPECT_THROW(read_surface(dir / "cut.tar.gz", "tet.off"), Error);
}

TEST(Archive, ErrorsInTheMemberNameTheArchiveAndTheMember) {
  TempDir dir;
  dir.write("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
  pack(dir, "bad.tar.gz", "bad.off");
  try {
    read_surface(dir / "bad.tar.gz", "bad.off");
    FAIL() << "no error for a triangle naming vertex 7 of 3";
  } catch (const Error& e) {
    EXPECT_THAT(e.file(), HasSubstr("bad.tar.gz"));
    EXPECT_THAT(e.file(), HasSubstr("bad.off"));
    EXPECT_EQ(e.line(), 6);
  }
}

TEST(Archive, MissingArchiveIsAnIoError) {
  TempDir dir;
  try {
    read_surface(dir / "nothing.tar.gz", "a.off");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIo);
  }
}

#ifdef TETCUT_CGAL_ARCHIVE
TEST(Archive, ReadsTheFemurFromDebiansCgalData) {
  const TriangleSurface femur = read_surface(TETCUT_CGAL_ARCHIVE, "data/meshes/femur.off");
  const TriangleSurface unpacked = read_surface(std::filesystem::path(TETCUT_REAL_DATA) / "femur.off");
  EXPECT_EQ(femur.vertices, unpacked.vertices);
  EXPECT_EQ(femur.triangles, unpacked.triangles);
}
#endif

}  // namespace
}  // namespace tetcut
