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
///
/// A blade moving through a mesh that itself moves between batches: sweep in material space.
/// Consecutive strips placed in world space meet there, but each is pulled back through the motion
/// at its own time, and where the material drifted across the blade between the two they do not
/// meet in the material, leaving a sliver of material uncut. Map each pose to rest space with
/// Cutter::to_rest when it is reached, and cut the strip between consecutive rest-space poses with
/// Cutter::cut: consecutive strips then share their edge exactly, and the incision is continuous.
TriangleSurface swept_blade(std::span<const BladePose> poses);

}  // namespace tetcut
