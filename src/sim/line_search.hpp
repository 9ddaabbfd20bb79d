#pragma once
// The constants of the backtracking line searches of the two Newton solvers (the tet simulator's
// integrator.cpp and the cloth's cloth.cpp), which accept a step by the same rule.

namespace tetcut::sim::detail {

// Armijo's sufficient decrease: accept t when E(x + t d) <= E(x) - kArmijo t (-g . d). 1e-4 is the
// customary choice (Nocedal and Wright, Numerical Optimization, 3.1): almost any decrease of a
// descent step is accepted, so full Newton steps are rarely shortened.
constexpr double kArmijo = 1e-4;
// The relative rounding of a sum of many energy terms: decreases below it cannot be seen, and the
// gradient decides there instead.
constexpr double kEnergyRounding = 1e-13;

}  // namespace tetcut::sim::detail
