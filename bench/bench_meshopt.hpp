// meshoptimizer's simplifier, run in the same process as tsm, for the
// simplification table of `tsm bench --simplify`. meshoptimizer is optional
// at build time: without it meshopt_available() is false.
#pragma once
#include <functional>

#include "tsm/mesh.hpp"

namespace tsm::bench {

bool meshopt_available();

struct MeshoptRun {
  bool ok = false;
  Mesh mesh;              // positions as given, the kept triangles
  double ms = 0;          // the one meshopt_simplify call that made `mesh` (thread CPU time)
  double own_error = 0;   // meshoptimizer's own error estimate, model units
  double measured = 0;    // by `measure`, model units
};

// The fewest triangles meshoptimizer's simplifier keeps whose distance to
// `in`, as `measure(in, result)` gives it, is at most `max_error`: a binary
// search on its target count measured by `search`, then `measure` stepping
// up while over; with its border free and locked (the better of the two).
// `in` must be all triangles. `lowest` bounds the search below.
using MeasureFn = std::function<double(const Mesh&, const Mesh&)>;
MeshoptRun meshopt_within(const Mesh& in, double max_error, size_t lowest, const MeasureFn& search,
                          const MeasureFn& measure);

}  // namespace tsm::bench
