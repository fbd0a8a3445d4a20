// dsreg — metrics W0 (vertices) and W2 (faces) of the regularization energy (the paper's §3.4
// scalar products, eq. 15–17, and the "metrics based on estimated local areas" of §6).
//
//  * identity: W0 = W2 = I (the paper's choice; RegularizationWeights left empty).
//  * area: W2 = the area of each face estimated from the normal field u, W0 = the dual area of
//    each vertex. Face f (a surfel with trivial normal n_f = ±e_a) gets its projected area
//        a_f = |u_f · n_f| · s_b · s_c,
//    s_b, s_c being the grid spacings along the surfel's two in-plane axes. Why: over a piece of
//    surface of area A and unit normal n, the surfels of axis a tile its projection along a, of
//    area |n_a| A; with u = n each of them counts |n_a| times its own area, so the piece gets
//    Σ_a |n_a| · |n_a| A = A, whereas plain surfel areas would sum to (|n_x|+|n_y|+|n_z|) A
//    (up to √3 A). This is the classical elementary-area estimator of digital geometry.
//    Vertex dual area: w0_i = ¼ Σ_{faces f ∋ i} a_f (each quad gives a quarter of its area to
//    each of its 4 vertices), so Σ_i w0_i = Σ_f a_f.
//
// Units: a_f and w0_i are physical areas (length²). Scaling W0 and W2 by the same factor scales
// E by that factor and leaves its minimizer unchanged, so this choice of unit only shows in the
// reported energies (length⁴ instead of length²).
// Floor: a face whose u_f is nearly parallel to its own plane would get a_f ≈ 0; a_f is floored
// at min_cosine · s_b · s_c (default min_cosine = 0.05, i.e. a tilt of about 87°), so W2 > 0,
// and then W0 ≥ ¼ (incident faces) · floor > 0 as eq. 15 requires.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/regularization.hpp"

namespace dsreg {

enum class MetricKind { Identity, Area };

/// "identity" or "area"; throws dsreg::Error listing the choices otherwise.
MetricKind parse_metric_kind(const std::string& name);
std::string metric_name(MetricKind kind);
std::vector<std::string> metric_names();

struct AreaMetricOptions {
    /// Floor of |u_f · n_f| (dimensionless, in (0, 1]).
    double min_cosine = 0.05;
};

struct AreaMetric {
    Eigen::VectorXd face_areas;    ///< a_f, one per face, length² (diagonal of W2)
    Eigen::VectorXd vertex_areas;  ///< ¼ Σ_{f ∋ i} a_f, one per vertex, length² (diagonal of W0)
};

/// The area metric of `surface` for the normal field `normals` (one unit vector per face).
/// Throws dsreg::Error if the field has the wrong size or min_cosine is not in (0, 1].
AreaMetric estimate_area_metric(const DigitalSurface& surface, const PointMatrix& normals,
                                const AreaMetricOptions& options = {});

/// Sets weights.vertex_weights / face_weights for `kind` (clears them for Identity).
void apply_metric(MetricKind kind, const DigitalSurface& surface, const PointMatrix& normals, RegularizationWeights& weights,
                  const AreaMetricOptions& options = {});

}  // namespace dsreg
