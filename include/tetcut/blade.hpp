#pragma once
// Turning a moving blade into cut triangles.

#include <tetcut/surface.hpp>

#include <span>

namespace tetcut {

/// A straight blade at one instant: the segment from `a` (e.g. where the edge leaves the handle)
/// to `b` (the tip).
struct BladePose {
  Vec3 a, b;
};

/// The surface a straight blade sweeps through successive poses: for each step the quad
/// (a_i, b_i, b_i+1, a_i+1), as two triangles sharing the diagonal a_i b_i+1. Steps share their
/// edges, so the strip has no gaps; triangles of zero area (the blade not moving at one end, or
/// moving along itself) are left out, decided exactly. Oriented by the first step: the normal is
/// (b_0 - a_0) x (a_1 - a_0). Feed the triangles of each step, or of a few steps, as one batch to
/// Cutter::cut or Cutter::cut_deformed.
TriangleSurface swept_blade(std::span<const BladePose> poses);

}  // namespace tetcut
