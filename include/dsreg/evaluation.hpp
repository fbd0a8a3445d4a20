// dsreg — evaluation against ground truth (the paper's §5): how close a mesh is to an implicit
// shape, and the multigrid convergence experiment of Fig. 7.
//
// Conventions shared by every function here:
//  * Lengths, distances and volumes are in physical units (the shape's coordinates); angles are
//    in degrees. Dividing a distance by the grid step h gives it "in units of h".
//  * ξ(p) is closest_point(shape, p) (implicit_shape.hpp); the distance of p to the shape's
//    surface is |p − ξ(p)|.
//  * Face normal of a mesh face (the paper's footnote 5): a triangle (a,b,c) has the unit normal
//    of (b−a)×(c−a); a quad (a,b,c,d) has the normalized mean of the unit normals of its
//    triangles (a,b,c) and (a,c,d). A face whose normal cannot be defined (zero area) is
//    "degenerate" and left out of normal statistics.
//  * Solid of a mesh (volume, inside test, triangle angles): each quad is split along its shorter
//    diagonal, exactly as `--triangulate` and the STL writer do (triangulate_shorter_diagonal).
//  * Clipped shapes (ImplicitShape::clipped): the box faces are part of the digitized object's
//    boundary but not of F = 0. Distance and normal statistics can leave out every point closer
//    than a margin to a clipped box face (see in_evaluation_region).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/solvers.hpp"
#include "dsreg/volume.hpp"

namespace dsreg {

// ---------------------------------------------------------------------------------------------
// Statistics

/// Statistics of a list of non-negative errors (all zero when the list is empty).
struct ErrorStats {
    std::int64_t count = 0;
    double mean = 0;  ///< arithmetic mean
    double l2 = 0;    ///< root mean square, sqrt(Σ e² / n)
    double linf = 0;  ///< maximum
    double p95 = 0;   ///< 95th percentile, nearest rank: the ⌈0.95·n⌉-th smallest value

    /// The same statistics of the errors multiplied by `factor` (e.g. 1/h for units of h).
    ErrorStats scaled(double factor) const;
};

ErrorStats error_stats(std::vector<double> errors);

/// Least-squares slope of log(y) against log(x) over the pairs with x > 0 and y > 0 (finite).
/// NaN when fewer than two such pairs remain or all their x are equal. An error in O(h^k)
/// has slope k when x = h.
double log_log_slope(const std::vector<double>& x, const std::vector<double>& y);

/// n values from `largest` down to `smallest`, equally spaced in log: largest·q^i with
/// q = (smallest/largest)^(1/(n−1)). Throws dsreg::Error unless largest ≥ smallest > 0 (finite)
/// and n ≥ 2 (n = 1 is accepted when largest = smallest).
std::vector<double> geometric_steps(double largest, double smallest, int count);

// ---------------------------------------------------------------------------------------------
// Mesh geometry

/// Unit normal of every face (triangles or quads, see above); a zero row for a degenerate face.
PointMatrix face_normals(const PointMatrix& vertices, const FaceMatrix& faces);

/// Number of faces whose normal (face_normals) points against their row of `field` (negative
/// dot product) or is undefined (degenerate face): faces folded over or turned inside out, e.g.
/// by a regularization that follows a field pointing inward. field: one vector per face.
std::int64_t count_faces_against_field(const PointMatrix& vertices, const FaceMatrix& faces, const PointMatrix& field);

/// Mean of the vertices of every face.
PointMatrix face_centroids(const PointMatrix& vertices, const FaceMatrix& faces);

/// Angle between two non-zero vectors, in degrees (0 … 180), accurate for tiny angles.
double angle_degrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

/// The triangles of a triangle or quad mesh (quads split along their shorter diagonal).
/// Throws dsreg::Error for faces of another size or indices out of range.
FaceMatrix mesh_triangles(const PointMatrix& vertices, const FaceMatrix& faces);

/// Signed volume enclosed by a closed triangle mesh, by the divergence theorem:
/// Σ a·(b×c)/6 over its triangles (a,b,c). Positive for outward (counter-clockwise) faces.
double enclosed_volume(const PointMatrix& vertices, const FaceMatrix& triangles);

/// Smallest interior angle of each triangle, in degrees (0 for a degenerate triangle).
std::vector<double> triangle_min_angles(const PointMatrix& vertices, const FaceMatrix& triangles);

/// Which voxel centres of `grid` lie inside the closed triangle mesh (1 inside, 0 outside),
/// indexed like the grid's voxels. Inside = an odd number of crossings of the ray from the
/// centre towards +x. One pass per voxel row: the triangles are bucketed by the rows their y-z
/// bounding box covers, each row collects and sorts its crossings once, so the cost is
/// O(voxels + crossings·log + triangles·rows per triangle). Rays through edges and vertices
/// are resolved by a symbolic perturbation of the ray (shared edges are evaluated identically
/// in their two triangles), so each crossing is counted exactly once.
std::vector<std::uint8_t> voxel_centres_inside(const PointMatrix& vertices, const FaceMatrix& triangles,
                                               const VoxelGrid& grid);

/// voxel_centres_inside kept up to date while vertices move (the repair's voxel sides): the
/// triangles stay bucketed by the voxel rows (j, k) their y-z bounding boxes cover, so an update
/// moves only the triangles it is given between buckets and classifies again only the rows they
/// covered before or cover now. Every classification equals voxel_centres_inside's at the same
/// positions.
class VoxelCentresInside {
public:
    /// Classifies every voxel centre of `grid` against the closed mesh. Throws dsreg::Error for a
    /// vertex index out of range.
    VoxelCentresInside(const PointMatrix& vertices, const FaceMatrix& triangles, const VoxelGrid& grid);

    /// The triangles `changed` (row indices of `triangles`) may have new vertices or new
    /// positions in `vertices`; every other triangle is as at the last call (same vertices, not
    /// moved). Returns the rows classified again, index j + ny·k, increasing. Throws dsreg::Error
    /// for a triangle count other than the constructor's or an index out of range.
    std::vector<std::int64_t> update(const PointMatrix& vertices, const FaceMatrix& triangles,
                                     const std::vector<std::int32_t>& changed);

    /// Whether the centre of voxel `index` (linear, as the grid's) is inside.
    bool is_inside(std::int64_t index) const {
        const std::int64_t row = index / grid_.dims[0], i = index - row * grid_.dims[0];
        return (bits_[std::size_t(row * words_per_row_ + i / 64)] >> (i % 64)) & 1u;
    }
    /// 1 where the voxel centre is inside, indexed like the grid's voxels.
    std::vector<std::uint8_t> inside() const;

private:
    struct RowBox {  ///< rows j0..j1 × k0..k1 (empty if j1 < j0 or k1 < k0)
        std::int32_t j0, j1, k0, k1;
    };
    RowBox rows_of(const PointMatrix& vertices, const FaceMatrix& triangles, Eigen::Index t) const;
    template <class Visit>
    void for_each_row(const RowBox& box, Visit visit) const;
    void classify(const PointMatrix& vertices, const FaceMatrix& triangles, const std::vector<std::int64_t>& rows);

    VoxelGrid grid_;
    std::vector<std::vector<std::int32_t>> row_triangles_;  ///< per row j + ny·k: the triangles that may cross its ray
    std::vector<RowBox> triangle_rows_;                     ///< per triangle: the rows listing it
    /// One bit per voxel centre, 1 inside; each row starts on a word of its own, so that rows are
    /// classified side by side without sharing a word (an eighth of a byte per voxel: the count of
    /// voxel centres runs on every binary volume, 512³ images included).
    std::int64_t words_per_row_ = 0;
    std::vector<std::uint64_t> bits_;
};

// ---------------------------------------------------------------------------------------------
// Ground truth of an implicit shape

/// Volume of the solid {F ≤ 0} ∩ box, by nested quadrature. Along each x line, F is a
/// polynomial in x whose sign changes are found exactly (the line is cut where F is monotone,
/// using the roots of its derivatives, and each root is polished to double precision), which
/// gives the chord length {F ≤ 0} ∩ box on that line. The chord lengths are integrated over y
/// (cross-section area), and the areas over z, by globally adaptive Simpson quadrature, each
/// started from cells_per_axis equal pieces (features thinner than about 1/cells_per_axis of the
/// box may be missed) and refined where the error estimate is largest (at silhouettes, where
/// the chord behaves like √distance), down to a relative error estimate of 1e-6 of the box
/// volume or a fixed budget of evaluations. Measured: relative error below 1e-7 for sphere1,
/// ellipsoid and torus against their exact volumes (tests/test_evaluation.cpp); about a
/// second for a quartic such as goursat on two cores. Throws dsreg::Error for cells_per_axis < 8.
double shape_volume(const ImplicitShape& shape, int cells_per_axis = 64);

/// True when p is at least `wall_margin` inside every clipped box face of the shape
/// (lower[a] + margin ≤ p[a] ≤ upper[a] − margin along each clipped axis a). Always true for
/// a shape without clipped axes.
bool in_evaluation_region(const ImplicitShape& shape, const Eigen::Vector3d& p, double wall_margin);

/// |p − ξ(p)| for every row of `points` (parallel).
std::vector<double> distances_to_surface(const ImplicitShape& shape, const PointMatrix& points);

/// Ground-truth normals of the digitized solid {F ≤ 0} ∩ box, one per surfel: a surfel whose
/// background voxel is background only because it lies outside a clipped box face (F ≤ 0
/// there) is a box-wall face and gets that face's axis normal; every other surfel gets
/// ∇F/|∇F| at ξ(surfel centre), as exact_normals() does. Identical to exact_normals() for a
/// shape without clipped axes. Needed for clipped shapes such as make_plane_shape: with the
/// plane's normal on the box walls as well, the alignment term would flatten the whole closed
/// surface onto one plane.
PointMatrix solid_exact_normals(const ImplicitShape& shape, const DigitalSurface& surface);

// ---------------------------------------------------------------------------------------------
// Evaluation of any mesh against a shape

struct MeshEvaluationOptions {
    /// Grid step for the voxel classification (digitize(shape, grid_step)); ≤ 0 skips it.
    double grid_step = 0;
    /// Points (vertices, face centroids) closer than this to a clipped box face are left out of
    /// the distance and normal statistics (physical units).
    double wall_margin = 0;
    int volume_cells = 64;  ///< cells_per_axis of shape_volume()
};

/// On how many voxel centres of a binary volume a closed mesh agrees with the volume (centre
/// inside the mesh ⇔ object voxel), over three sets of voxels:
///  * all the voxels of the grid (far from the surface nearly every one agrees, so on a large
///    box this share is close to 1 whatever the mesh);
///  * the object voxels ("object": a mesh that shrinks a thin part loses them);
///  * the voxels next to the digital surface: object and background voxels with a 6-neighbour of
///    the other kind, the border of the grid counting as background ("boundary"). Every voxel
///    a mesh can plausibly misclassify is there, from either side, so this share is the strict one.
struct VoxelClassification {
    std::int64_t correct = 0;  ///< voxel centres on which the mesh and the volume agree
    std::int64_t total = 0;    ///< voxels of the grid
    std::int64_t object_correct = 0, object_total = 0;
    std::int64_t boundary_correct = 0, boundary_total = 0;
    double share() const { return total > 0 ? double(correct) / double(total) : 0.0; }
    double object_share() const { return object_total > 0 ? double(object_correct) / double(object_total) : 0.0; }
    double boundary_share() const {
        return boundary_total > 0 ? double(boundary_correct) / double(boundary_total) : 0.0;
    }
};

/// Classifies the voxel centres of `volume` by the closed triangle or quad mesh (quads split
/// along their shorter diagonal, voxel_centres_inside) against the volume's own labels. Throws
/// dsreg::Error for an empty mesh or faces that are not triangles or quads.
VoxelClassification classify_voxel_centres(const PolygonMesh& mesh, const BinaryVolume& volume);

struct MeshEvaluation {
    std::int64_t vertices_evaluated = 0;
    std::int64_t vertices_outside_region = 0;  ///< left out: within wall_margin of a clipped box face
    std::int64_t faces_evaluated = 0;
    std::int64_t faces_outside_region = 0;
    std::int64_t faces_degenerate = 0;  ///< no normal (zero area) or no true normal (singular point)

    ErrorStats vertex_distance;   ///< |p − ξ(p)| per vertex, physical units
    ErrorStats normal_angle_deg;  ///< angle between face normal and true normal at ξ(face centroid)
    std::vector<double> face_angle_deg;  ///< that angle per face (NaN where not evaluated)

    double mesh_volume = 0;            ///< signed, divergence theorem
    double shape_volume = 0;           ///< shape_volume(shape)
    double relative_volume_error = 0;  ///< (mesh_volume − shape_volume) / shape_volume

    bool has_voxel_classification = false;
    VoxelClassification voxels;

    std::int64_t triangles = 0;
    double triangle_min_angle_min_deg = 0;   ///< smallest angle of the triangulated mesh
    double triangle_min_angle_mean_deg = 0;  ///< mean over triangles of their smallest angle
};

/// Evaluates a triangle or quad mesh (e.g. read_mesh() of a file of any tool) against `shape`.
/// Throws dsreg::Error for an empty mesh or faces that are not triangles or quads.
MeshEvaluation evaluate_mesh(const PolygonMesh& mesh, const ImplicitShape& shape, const MeshEvaluationOptions& options);

// ---------------------------------------------------------------------------------------------
// Multigrid convergence experiment (Fig. 7)

enum class InputNormalField {
    Exact,              ///< solid_exact_normals
    /// integral_invariant_normals (kernel ii_kernel) with r = radius_k · h^(1/3). For a
    /// shape clipped by its box (the tilted plane), the field is computed on a digitization in
    /// a box enlarged by r + 2h, so that no ball sees the box walls, and the faces on the walls
    /// get the wall's normal (docs/convergence.md).
    IntegralInvariant,
};

struct ConvergenceOptions {
    InputNormalField normals = InputNormalField::Exact;
    double radius_k = 3.0;  ///< II radius r = radius_k · h^(1/3), physical units
    IntegralInvariantKernel ii_kernel = IntegralInvariantKernel::biweight;  ///< ball: the paper's II
    bool ii_extrapolate = false;  ///< extrapolated_integral_invariant_normals instead
    double alpha_k = 1e-5;  ///< α = alpha_k · h² (Fig. 7: 1e-5)
    double beta = 1.0;
    double gamma = 0.0;
    Connectivity connectivity = Connectivity::TwentySix;
    SolverOptions solver;
    /// Region of the statistics (see in_evaluation_region), physical units; e.g. 0.25 for the
    /// plane in [-1,1]³ keeps the seams with the box walls out. A vertex (face) is in the
    /// region when its digital position p (centroid of p) is.
    double wall_margin = 0;
};

/// L2 (root mean square) and L∞ (maximum) of a per-element error.
struct ErrorNorms {
    double l2 = 0;
    double linf = 0;
};

/// One grid step of the experiment. Over the vertices / faces of the region:
///  * normal:  |u*_f − u_f| (length of the difference of unit vectors), u* = face_normals(p*);
///  * p:       |p_i − ξ(p_i)|, the digital surface's vertices against ∂X;
///  * pstar:   |p*_i − ξ(p*_i)|, the regularized vertices against ∂X;
///  * ratio:   pstar / p, separately for L2 and L∞ (< 1: p* is closer to ∂X than p);
///  * closer_share: share of vertices with |p*_i − ξ(p*_i)| < |p_i − ξ(p_i)|.
struct ConvergenceStep {
    double h = 0;
    double radius = 0;  ///< II radius (0 for exact normals)
    double alpha = 0;
    std::int64_t faces = 0, vertices = 0;                      ///< whole digital surface
    std::int64_t faces_evaluated = 0, vertices_evaluated = 0;  ///< in the region
    std::int64_t faces_degenerate = 0;                         ///< u* undefined (left out)
    ErrorNorms normal, p, pstar, ratio;
    double closer_share = 0;
    double relative_residual = 0;  ///< of the linear solve
    double seconds = 0;            ///< wall time of the whole step
};

/// Digitizes `shape` at h, estimates u, regularizes with α = alpha_k·h², β, γ and measures.
/// Throws dsreg::Error (e.g. empty digitization, failed solve, no vertex in the region).
ConvergenceStep run_convergence_step(const ImplicitShape& shape, double h, const ConvergenceOptions& options);

/// Least-squares log-log slopes of each curve over the steps (NaN where undefined).
struct ConvergenceSlopes {
    ErrorNorms normal, p, pstar, ratio;
};
ConvergenceSlopes convergence_slopes(const std::vector<ConvergenceStep>& steps);

// ---------------------------------------------------------------------------------------------
// Log-log plots as SVG text

struct PlotCurve {
    std::string label;
    std::vector<double> x, y;  ///< points with x ≤ 0 or y ≤ 0 are not drawn
};

struct PlotPanel {
    std::string title;
    std::string y_label;
    std::vector<PlotCurve> curves;
    bool reference_slope_one = true;  ///< draw a dashed O(h) guide line
};

/// A self-contained SVG document: the panels on a grid of `columns` columns, each a log-log
/// plot with decade ticks, markers, a legend and the common x label. Pure function (no I/O).
std::string log_log_plot_svg(const std::string& title, const std::string& x_label,
                             const std::vector<PlotPanel>& panels, int columns = 2);

/// The four rows of Fig. 7 for one shape (|u*−u|, p vs ∂X, p* vs ∂X, p*/p), L2 and L∞ each,
/// with the fitted slopes in the legend.
std::string convergence_plot_svg(const std::string& title, const std::vector<ConvergenceStep>& steps);

}  // namespace dsreg
