// Cuts the paper's Figure 4 through the installed library: prints its piece count (289).
#include <tetcut/cutter.hpp>
#include <tetcut/figures.hpp>

#include <cstdio>

int main() {
  tetcut::Cutter cutter(tetcut::figures::figure4_cube());
  cutter.cut(tetcut::figures::figure4_planes());
  std::printf("%d\n", static_cast<int>(cutter.result().mesh.num_pieces()));
  return 0;
}
