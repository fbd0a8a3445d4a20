// dsreg — the exact tests behind triangle_self_intersections (internal to src/validity), for the
// incremental check, which decides only the pairs of the triangles that moved.
#pragma once

#include <cstdint>

#include "dsreg/mesh.hpp"

namespace dsreg::validity_internal {

/// Whether the corners of triangle t (a row of `triangles`) are collinear, exactly.
bool triangle_is_degenerate(const PointMatrix& vertices, const FaceMatrix& triangles, std::int64_t t);

/// Whether non-degenerate triangles a and b meet beyond the vertices they share by index, exactly:
/// sharing an edge, when they are coplanar and on the same side of it; sharing a vertex, when the
/// edge of either opposite that vertex meets the other triangle; sharing nothing, when they meet.
bool triangles_meet_beyond_shared_indices(const PointMatrix& vertices, const FaceMatrix& triangles, std::int64_t a,
                                          std::int64_t b);

}  // namespace dsreg::validity_internal
