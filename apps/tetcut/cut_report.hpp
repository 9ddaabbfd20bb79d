#pragma once
// The outputs and the report of a cut (tetcut cut, tetcut demo) or an embedding (tetcut embed):
// the options that name them, the summary printed, and the JSON report's schema.

#include <tetcut/cutter.hpp>
#include <tetcut/io.hpp>

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "common.hpp"

namespace tetcut::cli {

/// A batch of cut triangles and the name warnings give it (its file).
struct NamedBatch {
  std::string name;
  TriangleSurface triangles;
};

/// Where a cut's results go; empty paths are not written.
struct CutOutputs {
  fs::path mesh, surface, report;
  bool binary = false;
  bool deformed = false;  // write current (deformed) positions instead of rest positions
  TetMeshWriteOptions mesh_options;

  /// Registers --out-mesh, --out-surface, --report (whose contents `report_keys` names) and --binary.
  void add(CLI::App* command, const std::string& report_keys);

  /// Checks every output before any work, so a typo costs nothing and nothing is half written.
  void check(const std::vector<fs::path>& inputs) const;
};

/// What a run reports besides the result itself.
struct RunSummary {
  std::string headline;  // the first line printed
  Json report;           // the report's first keys (inputs)
  Index triangles = 0, skipped = 0, inverted = 0;
  bool world_space = false;
  Json timings;          // stages before the surface; surface and write follow
  Json extra;            // keys appended to the report
  bool peak_memory = false;  // report the process's peak resident memory
};

/// Writes the outputs of a cut (or an embedding) of `mesh`, prints a summary and writes the report.
void write_and_report(const TetMesh& mesh, const CutResult& result, const CutOutputs& outputs, const RunSummary& run);

/// Cuts `mesh` by the batches in order, prints warnings and a summary, and writes the outputs. With
/// `deformed` positions, the batches are placed in world space on that configuration.
CutResult cut_and_report(const std::string& name, const TetMesh& mesh, const std::vector<NamedBatch>& batches,
                         const CutOutputs& outputs, double read_seconds, const Points* deformed = nullptr);

}  // namespace tetcut::cli
