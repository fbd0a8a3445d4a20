// dsreg — named implicit shapes, Gauss digitization, true normals and closest-point projection.
#include "dsreg/implicit_shape.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <new>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "dsreg/error.hpp"
#include "polynomial_eval.hpp"

namespace dsreg {
namespace {

// ---------------------------------------------------------------------------------------------
// Named shapes

struct NamedShape {
    const char* name;
    const char* formula;  ///< exactly as in DESIGN.md
    Eigen::Vector3d lower;
    Eigen::Vector3d upper;
    std::array<bool, 3> clipped;
};

/// Extra room added around an analytic bound, so that F > 0 holds strictly on the box faces.
constexpr double bound_margin_fraction = 0.05;

/// Box [-e - m, e + m] per axis around the analytic extents e, with m = 5% of the largest extent.
NamedShape bounded(const char* name, const char* formula, const Eigen::Vector3d& extent) {
    const Eigen::Vector3d half = extent.array() + bound_margin_fraction * extent.maxCoeff();
    return NamedShape{name, formula, -half, half, {false, false, false}};
}

/// A clip box [-half, half] (the shape is unbounded along every axis flagged in `clipped`).
NamedShape clipped_box(const char* name, const char* formula, const Eigen::Vector3d& half,
                       std::array<bool, 3> clipped) {
    return NamedShape{name, formula, -half, half, clipped};
}

/// Largest root of a·s² + b·s + c = 0 (a > 0, real roots assumed).
double largest_quadratic_root(double a, double b, double c) {
    return (-b + std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a);
}

/// The community's shapes. Each box is derived from the formula (see the comment at each entry).
const std::vector<NamedShape>& named_shapes() {
    static const std::vector<NamedShape> shapes = [] {
        const double r30 = std::sqrt(30.0), r45 = std::sqrt(45.0), r90 = std::sqrt(90.0);
        // goursat: F = 0.03·Σx⁴ − 2·Σx² − 8. Per axis g(t) = 0.03t⁴ − 2t² ≥ −100/3 (minimum at
        // t² = 100/3), so F ≤ 0 forces g(x) ≤ 8 + 2·100/3, i.e. x² ≤ the largest root s of
        // 0.03s² − 2s − (8 + 200/3) = 0 (s ≈ 93.3, |x| ≤ 9.66).
        const double goursat = std::sqrt(largest_quadratic_root(0.03, -2.0, -(8.0 + 200.0 / 3.0)));
        // goursat-hole: F = Σx⁴ − 8·Σx² + 30. Per axis t⁴ − 8t² ≥ −16 (at t² = 4), so F ≤ 0 forces
        // x⁴ − 8x² ≤ 2, i.e. x² ≤ 4 + √18 (|x| ≤ 2.87).
        const double hole = std::sqrt(largest_quadratic_root(1.0, -8.0, -2.0));
        return std::vector<NamedShape>{
            // Spheres: radius 1 and 9.
            bounded("sphere1", "x^2+y^2+z^2-1", {1.0, 1.0, 1.0}),
            bounded("sphere9", "x^2+y^2+z^2-81", {9.0, 9.0, 9.0}),
            // 3x² + 2y² + z² ≤ 90: semi-axes √30, √45, √90.
            bounded("ellipsoid", "3*x^2+2*y^2+z^2-90", {r30, r45, r90}),
            // x² + 2z² ≤ 90: |x| ≤ √90, |z| ≤ √45, any y — clipped to |y| ≤ 10.
            NamedShape{"cylinder", "x^2+2*z^2-90",
                       Eigen::Vector3d(-(r90 + bound_margin_fraction * r90), -10.0, -(r45 + bound_margin_fraction * r90)),
                       Eigen::Vector3d(r90 + bound_margin_fraction * r90, 10.0, r45 + bound_margin_fraction * r90),
                       {false, true, false}},
            // (|p|² + 32)² ≤ 144ρ² (ρ² = x² + y²) ⟺ |p|² + 32 ≤ 12ρ ⟺ (ρ − 6)² + z² ≤ 4:
            // the solid torus R = 6, r = 2, so ρ ≤ 8 and |z| ≤ 2.
            bounded("torus", "(x^2+y^2+z^2+6*6-2*2)^2-4*6*6*(x^2+y^2)", {8.0, 8.0, 2.0}),
            // x⁴ ≤ x⁴ + y⁴ + z⁴ ≤ 6561 = 9⁴.
            bounded("rcube", "x^4+y^4+z^4-6561", {9.0, 9.0, 9.0}),
            bounded("goursat", "-1*(8-0.03*x^4-0.03*y^4-0.03*z^4+2*x^2+2*y^2+2*z^2)", {goursat, goursat, goursat}),
            bounded("goursat-hole", "x^4+y^4+z^4-2*4*(x^2+y^2+z^2)+2*4*4-2", {hole, hole, hole}),
            // F ≤ 0 ⟺ |p|² + 1000·(x²+y²)(x²+z²)(y²+z²) ≥ 10000: the unbounded complement of a
            // "thistle" whose six spikes reach |x| = 100 along the axes. Clipped to the usual
            // [-10, 10]³ of the digital-geometry community: a box with a spiky cavity.
            clipped_box("distel", "10000-(x^2+y^2+z^2+1000*(x^2+y^2)*(x^2+z^2)*(y^2+z^2))", {10.0, 10.0, 10.0},
                        {true, true, true}),
            // Every term is ≥ 0, so 4x² ≤ 100, 4y² ≤ 100, 3z² ≤ 100.
            bounded("leopold", "(x^2*y^2*z^2+4*x^2+4*y^2+3*z^2)-100", {5.0, 5.0, std::sqrt(100.0 / 3.0)}),
            // F ≤ 0 ⟺ |x| ≤ y² + z²: unbounded along every axis; two paraboloid cups x = ±(y²+z²)
            // meeting at the origin. Clipped so that the cups (radius √5 at |x| = 5) lie inside
            // the y and z extent.
            clipped_box("diabolo", "x^2-(y^2+z^2)^2", {5.0, 3.0, 3.0}, {true, true, true}),
            // F = −H with H the classical heart (x² + 9/4 y² + z² − 1)³ − x²z³ − 9/80 y²z³; the
            // solid heart {H ≤ 0} spans about |x| ≤ 1.14, |y| ≤ 0.68, −1 ≤ z ≤ 1.23. {F ≤ 0} is its
            // unbounded complement, clipped by a box around the heart: a box with a heart cavity.
            clipped_box("heart", "-1*(x^2+2.25*y^2+z^2-1)^3+x^2*z^3+0.1125*y^2*z^3", {1.5, 1.0, 1.5},
                        {true, true, true}),
            // F = −G with G = 0.9(y²+z²−1)² + (x²+y²−1)³. G ≤ 0 needs x² + y² ≤ 1 and then
            // 0.9(y²+z²−1)² ≤ 1, so y² + z² ≤ 1 + 1/√0.9: the solid lies in |x|, |y| ≤ 1,
            // |z| ≤ 1.44. {F ≤ 0} is its unbounded complement, clipped by a box around it.
            clipped_box("crixxi", "-0.9*(y^2+z^2-1)^2-(x^2+y^2-1)^3", {1.5, 1.5, 2.0}, {true, true, true}),
        };
    }();
    return shapes;
}

const NamedShape* find_named_shape(const std::string& name) {
    for (const NamedShape& shape : named_shapes())
        if (name == shape.name) return &shape;
    return nullptr;
}

std::string joined_shape_names() {
    std::string names;
    for (const NamedShape& shape : named_shapes()) names += (names.empty() ? "" : ", ") + std::string(shape.name);
    return names;
}

std::string format_point(const Eigen::Vector3d& p) {
    std::ostringstream out;
    out.precision(17);
    out << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
    return out.str();
}

// ---------------------------------------------------------------------------------------------
// Digitization

/// Grid index range along one axis: first = floor(lower/h) − 1, last = ceil(upper/h) + 1.
struct IndexRange {
    std::int64_t first;
    std::int64_t count;
};

IndexRange index_range(double lower, double upper, double h, const char* axis_name) {
    const double first = std::floor(lower / h) - 1.0;
    const double last = std::ceil(upper / h) + 1.0;
    constexpr double limit = 1e15;  // far beyond any grid we accept, well inside int64
    if (!(std::abs(first) < limit && std::abs(last) < limit))
        throw Error(std::string("digitize: the box is too large for grid step h along ") + axis_name);
    return IndexRange{static_cast<std::int64_t>(first), static_cast<std::int64_t>(last - first) + 1};
}

void check_digitization_input(const ImplicitShape& shape, double h) {
    if (!std::isfinite(h) || h <= 0.0)
        throw Error("digitize: the grid step h must be a finite positive number (got " + std::to_string(h) + ")");
    if (!shape.lower.allFinite() || !shape.upper.allFinite() || (shape.lower.array() > shape.upper.array()).any())
        throw Error("digitize: shape '" + shape.name + "' has an invalid box " + format_point(shape.lower) + " – " +
                    format_point(shape.upper));
}

/// What every z slice of a digitization needs: index ranges, the box test and, for each power
/// e of x, the row of values (h·i)^e over the grid columns (the layout detail::evaluate_row
/// takes; contiguous, so that its per-voxel sums vectorize).
class DigitizationGrid {
public:
    DigitizationGrid(const ImplicitShape& shape, double h)
        : shape_(shape),
          h_(h),
          range_{index_range(shape.lower.x(), shape.upper.x(), h, "x"),
                 index_range(shape.lower.y(), shape.upper.y(), h, "y"),
                 index_range(shape.lower.z(), shape.upper.z(), h, "z")} {
        box_.hi = {range_[0].count, range_[1].count, range_[2].count};
    }

    const IndexRange& range(int axis) const { return range_[axis]; }
    double voxel_count() const { return double(range_[0].count) * double(range_[1].count) * double(range_[2].count); }

    /// Digitize only the voxels of `box` (inside the grid); slices and rows are then those of the box.
    void restrict_to(const VoxelBox& box) { box_ = box; }
    const VoxelBox& box() const { return box_; }

    /// Physical coordinate h·(first + index) of a grid index along an axis.
    double coordinate(int axis, std::int64_t index) const { return h_ * double(range_[axis].first + index); }
    bool in_box(int axis, std::int64_t index) const {
        const double c = coordinate(axis, index);
        return c >= shape_.lower[axis] && c <= shape_.upper[axis];
    }

    /// Fills x_powers_ and column_in_box_ (after the size checks, as they take memory).
    void prepare_columns() {
        const std::size_t nx = static_cast<std::size_t>(box_.size()[0]);
        const int max_power = shape_.polynomial.max_exponent(0);
        x_powers_.assign((static_cast<std::size_t>(max_power) + 1) * nx, 0.0);
        column_in_box_.assign(nx, 0);
        double powers[detail::power_table_size];
        for (std::size_t i = 0; i < nx; ++i) {
            const std::int64_t index = box_.lo[0] + std::int64_t(i);
            detail::fill_powers(coordinate(0, index), max_power, powers);
            for (int e = 0; e <= max_power; ++e) x_powers_[static_cast<std::size_t>(e) * nx + i] = powers[e];
            column_in_box_[i] = in_box(0, index);
        }
    }

    /// Digitizes slice k of the grid (box_.lo[2] ≤ k < box_.hi[2]) into `slice` (the box's rows:
    /// nx·ny bytes of the box); `row_sum` is scratch space of nx doubles.
    void digitize_slice(std::int64_t k, std::uint8_t* slice, std::vector<double>& row_sum) const {
        if (!in_box(2, k)) return;
        const std::size_t nx = static_cast<std::size_t>(box_.size()[0]);
        double pz[detail::power_table_size], py[detail::power_table_size];
        detail::fill_powers(coordinate(2, k), shape_.polynomial.max_exponent(2), pz);
        for (std::int64_t j = box_.lo[1]; j < box_.hi[1]; ++j) {
            if (!in_box(1, j)) continue;
            detail::fill_powers(coordinate(1, j), shape_.polynomial.max_exponent(1), py);
            // The same kernel as Polynomial::value(): identical results at every voxel.
            detail::evaluate_row(shape_.polynomial, py, pz, x_powers_.data(), nx, row_sum.data());
            std::uint8_t* row = slice + static_cast<std::size_t>(j - box_.lo[1]) * nx;
            for (std::size_t i = 0; i < nx; ++i) row[i] = (column_in_box_[i] && row_sum[i] <= 0.0) ? 1 : 0;
        }
    }

    /// The grid of the whole digitization.
    VoxelGrid voxel_grid() const {
        VoxelGrid grid;
        grid.dims = {range_[0].count, range_[1].count, range_[2].count};
        grid.spacing = Eigen::Vector3d::Constant(h_);
        grid.origin = Eigen::Vector3d(coordinate(0, 0), coordinate(1, 0), coordinate(2, 0));
        return grid;
    }

private:
    const ImplicitShape& shape_;
    double h_;
    IndexRange range_[3];
    VoxelBox box_;
    std::vector<double> x_powers_;
    std::vector<std::uint8_t> column_in_box_;
};

// ---------------------------------------------------------------------------------------------
// Closest point

/// F = a·|p|² + b·p + c = a·(|p − centre|² − radius²), as detected from the monomials.
struct SphereForm {
    Eigen::Vector3d centre;
    double radius_squared;
};

std::optional<SphereForm> as_sphere(const Polynomial& f) {
    if (f.degree() != 2) return std::nullopt;
    double a[3] = {0.0, 0.0, 0.0};  // coefficients of x², y², z²
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    double c = 0.0;
    for (const Polynomial::Monomial& m : f.monomials()) {
        const int degree = m.ex + m.ey + m.ez;
        const int axis = m.ex > 0 ? 0 : m.ey > 0 ? 1 : 2;
        if (degree == 2) {
            if (m.ex != 2 && m.ey != 2 && m.ez != 2) return std::nullopt;  // a cross term
            a[axis] = m.coefficient;
        } else if (degree == 1) {
            b[axis] = m.coefficient;
        } else {
            c = m.coefficient;
        }
    }
    if (a[0] == 0.0 || a[0] != a[1] || a[1] != a[2]) return std::nullopt;
    const Eigen::Vector3d centre = -b / (2.0 * a[0]);
    return SphereForm{centre, centre.squaredNorm() - c / a[0]};
}

Eigen::Vector3d closest_point_on_sphere(const SphereForm& sphere, const Eigen::Vector3d& p) {
    if (sphere.radius_squared < 0.0) throw Error("closest_point: the sphere F = 0 is empty (imaginary radius)");
    const double radius = std::sqrt(sphere.radius_squared);
    const Eigen::Vector3d offset = p - sphere.centre;
    const double distance = offset.norm();
    if (distance == 0.0) return sphere.centre + radius * Eigen::Vector3d::UnitX();  // every point is closest
    return sphere.centre + (radius / distance) * offset;
}

/// F = g·p + c: ξ = p − F(p)·g/|g|².
Eigen::Vector3d closest_point_on_plane(const Polynomial& f, const Eigen::Vector3d& p) {
    const Eigen::Vector3d g = f.gradient(p);
    return p - (f.value(p) / g.squaredNorm()) * g;
}

/// Closest point of F = 0 for a general polynomial, in two stages.
///
/// 1. Onto the surface (move_onto_surface): damped Newton on F along the gradient,
///    x ← x − t·F·∇F/|∇F|², halving t until |F| decreases. Where Newton is slow because F = 0 is
///    a multiple root (near a singular point of the surface, where ∇F → 0) two more steps are
///    tried (Newton on F/|∇F| and a modified Newton step on F²), and a sign change of F along
///    the step is bracketed and bisected. Long steps are sampled so that they never jump over
///    a thin part of the shape. If this ascent/descent of F stalls at a critical point of F
///    off the surface, the nearest sign change along rays from p is used instead.
/// 2. Along the surface (descend_distance): from a surface point ξ, a Newton step for the
///    distance in the tangent plane (with the Hessian of the Lagrangian made positive
///    definite), or else a step along the tangential part of p − ξ, each backtracked or
///    extended, followed by stage 1, and kept only if it brings ξ closer to p. So |p − ξ|
///    never grows, and the search ends at a point where p − ξ is parallel to ∇F(ξ) or where
///    no step gets closer (a local minimum of the distance: at a singular point, or at
///    rounding level).
/// A budget of polynomial evaluations bounds the time spent on pathological points; the best
/// surface point found so far is returned when it runs out.
class ClosestPointSearch {
public:
    ClosestPointSearch(const ImplicitShape& shape, const Eigen::Vector3d& p)
        : f_(shape.polynomial), abs_f_(absolute_coefficients(f_)), p_(p), scale_(length_scale(shape, p)) {}

    Eigen::Vector3d run() {
        Eigen::Vector3d xi = p_;
        if (!move_onto_surface(xi, max_surface_iterations)) {
            xi = p_;
            if (!nearest_crossing_on_rays(xi)) fail("F = 0 is not found near the point");
        }
        descend_distance(xi);
        return xi;
    }

private:
    static constexpr int max_descent_iterations = 200;
    static constexpr int max_surface_iterations = 200;     // from p
    static constexpr int max_candidate_iterations = 40;    // from a point next to the surface
    static constexpr int max_bisections = 200;
    static constexpr long evaluation_budget = 50000;  // polynomial evaluations per call

    // --- set-up ---------------------------------------------------------------------------

    static Polynomial absolute_coefficients(const Polynomial& f) {
        std::vector<Polynomial::Monomial> monomials = f.monomials();
        for (Polynomial::Monomial& m : monomials) m.coefficient = std::abs(m.coefficient);
        return Polynomial::from_monomials(std::move(monomials));
    }

    /// A length for relative tolerances and step limits: the size of the scene.
    static double length_scale(const ImplicitShape& shape, const Eigen::Vector3d& p) {
        double scale = std::max(1.0, p.norm());
        if (shape.lower.allFinite() && shape.upper.allFinite())
            scale = std::max({scale, shape.lower.norm(), shape.upper.norm()});
        return scale;
    }

    /// Tangential residual at which ξ is the closest point to double precision.
    double stop_tolerance() const { return 1e-13 * scale_; }
    /// |F|/|∇F| (a first-order distance to F = 0) below which a point counts as on the surface.
    double on_surface_tolerance() const { return 1e-15 * scale_; }
    /// The same, when rounding stops further progress.
    double stalled_on_surface_tolerance() const { return 1e-10 * scale_; }

    // --- evaluations (counted) -------------------------------------------------------------

    double value(const Eigen::Vector3d& x) const {
        evaluations_ += 1;
        return f_.value(x);
    }
    Eigen::Vector3d gradient(const Eigen::Vector3d& x) const {
        evaluations_ += 1;
        return f_.gradient(x);
    }
    Eigen::Matrix3d hessian(const Eigen::Vector3d& x) const {
        evaluations_ += 2;
        return f_.hessian(x);
    }
    bool out_of_budget() const { return evaluations_ > evaluation_budget; }

    /// Σ|c|·|x|^a·|y|^b·|z|^c over the monomials: bounds the rounding error of F(x).
    double term_magnitude(const Eigen::Vector3d& x) const {
        evaluations_ += 1;
        return abs_f_.value(x.cwiseAbs());
    }

    /// |F(x)| is below `factor` times the size of its rounding error: F(x) is zero as far as
    /// double precision can tell.
    bool at_noise_level(double fx, const Eigen::Vector3d& x, double factor) const {
        return std::abs(fx) <= factor * std::numeric_limits<double>::epsilon() * term_magnitude(x);
    }

    static bool opposite_signs(double a, double b) { return (a < 0.0 && b > 0.0) || (a > 0.0 && b < 0.0); }

    // --- stage 1: onto the surface ------------------------------------------------------------

    /// A root of F on the segment [a, b], where F(a) and F(b) have opposite signs (bisection).
    Eigen::Vector3d bisect(Eigen::Vector3d a, double fa, Eigen::Vector3d b) const {
        for (int iteration = 0; iteration < max_bisections; ++iteration) {
            const Eigen::Vector3d middle = 0.5 * (a + b);
            if ((b - a).norm() <= on_surface_tolerance() || middle == a || middle == b) break;
            const double fm = value(middle);
            if (fm == 0.0) return middle;
            if (opposite_signs(fa, fm)) {
                b = middle;
            } else {
                a = middle;
                fa = fm;
            }
        }
        return std::abs(fa) <= std::abs(value(b)) ? a : b;
    }

    Eigen::Vector3d capped(const Eigen::Vector3d& step) const {
        const double max_step = scale_;  // never jump across the scene
        const double length = step.norm();
        return length > max_step ? Eigen::Vector3d(step * (max_step / length)) : step;
    }

    struct Trial {
        Eigen::Vector3d step;
        double t;   ///< fraction of the step taken
        double fx;  ///< F(x − t·step)
    };

    /// The largest t in {1, 1/2, 1/4, …} with |F(x − t·step)| < (1 − 1e-4·t)·|F(x)|, if any.
    std::optional<Trial> backtrack(const Eigen::Vector3d& x, double fx, const Eigen::Vector3d& step) const {
        if (!step.allFinite()) return std::nullopt;
        for (double t = 1.0; t > 1e-12; t *= 0.5) {
            const double f_new = value(x - t * step);
            if (std::abs(f_new) < (1.0 - 1e-4 * t) * std::abs(fx)) return Trial{step, t, f_new};
        }
        return std::nullopt;
    }

    /// Steps for where Newton on F is slow because F = 0 is a multiple root (near a singular
    /// point of the surface, ∇F → 0): Newton on d = F/|∇F|, which has a simple root there
    /// (Schröder's method), and a Newton step minimizing F²/2 with its Hessian ∇F∇Fᵀ + F·H made
    /// positive definite, which follows curved valleys of |F| where the others zigzag.
    std::vector<Eigen::Vector3d> slow_progress_steps(const Eigen::Vector3d& x, double fx,
                                                     const Eigen::Vector3d& g) const {
        std::vector<Eigen::Vector3d> steps;
        const Eigen::Matrix3d h = hessian(x);
        const double g2 = g.squaredNorm();
        // ∇d = (∇F − F·H∇F/|∇F|²)/|∇F|; step = d·∇d/|∇d|².
        const Eigen::Vector3d grad_d = (g - (fx / g2) * (h * g)) / std::sqrt(g2);
        const double grad_d2 = grad_d.squaredNorm();
        if (grad_d2 > 0.0 && std::isfinite(grad_d2)) steps.push_back((fx / std::sqrt(g2) / grad_d2) * grad_d);
        // Modified Newton on F²/2: gradient F·∇F, Hessian ∇F∇Fᵀ + F·H with |eigenvalues|.
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(g * g.transpose() + fx * h);
        const Eigen::Vector3d magnitudes = eigen.eigenvalues().cwiseAbs();
        const double floor = 1e-12 * magnitudes.maxCoeff();
        if (floor > 0.0) {
            const Eigen::Vector3d inverse = magnitudes.cwiseMax(floor).cwiseInverse();
            const Eigen::Matrix3d& v = eigen.eigenvectors();
            steps.push_back(v * inverse.asDiagonal() * v.transpose() * (fx * g));
        }
        return steps;
    }

    /// A root of F on the line x − s·step, s ∈ (0, 16], if F changes sign there (bisection).
    std::optional<Eigen::Vector3d> bracketed_root(const Eigen::Vector3d& x, double fx,
                                                  const Eigen::Vector3d& step) const {
        for (double reach = 1.0; reach <= 16.0 && reach * step.norm() <= scale_; reach *= 2.0) {
            const Eigen::Vector3d end = x - reach * step;
            if (opposite_signs(fx, value(end))) return bisect(x, fx, end);
        }
        return std::nullopt;
    }

    /// For a long move x → x − move: the first root of F along it if F changes sign at one of a
    /// few sample points, so that a step never jumps over a thin part of the shape (a step whose
    /// end has the same sign as x could have crossed the surface twice).
    std::optional<Eigen::Vector3d> first_crossing(const Eigen::Vector3d& x, double fx,
                                                  const Eigen::Vector3d& move) const {
        constexpr int samples = 8;
        if (move.norm() <= 1e-3 * scale_) return std::nullopt;  // too short to hide a feature
        Eigen::Vector3d previous = x;
        double previous_value = fx;
        for (int k = 1; k <= samples; ++k) {
            const Eigen::Vector3d point = x - (double(k) / samples) * move;
            const double point_value = value(point);
            if (point_value == 0.0) return point;
            if (opposite_signs(previous_value, point_value)) return bisect(previous, previous_value, point);
            previous = point;
            previous_value = point_value;
        }
        return std::nullopt;
    }

    /// Moves x onto F = 0 (see the class comment). False if F = 0 is not reached.
    bool move_onto_surface(Eigen::Vector3d& x, int max_iterations) const {
        int nudges = 0;
        for (int iteration = 0; iteration < max_iterations && !out_of_budget(); ++iteration) {
            const double fx = value(x);
            if (fx == 0.0 || at_noise_level(fx, x, 4.0)) return true;
            const Eigen::Vector3d g = gradient(x);
            const double g2 = g.squaredNorm();
            if (!(g2 > 0.0) || !std::isfinite(g2)) {
                // A critical point of F: Newton has no direction. Step aside, a few times at most.
                if (++nudges > 3) return false;
                x += 1e-7 * scale_ * Eigen::Vector3d(0.5773, 0.3341, 0.7452);
                continue;
            }
            const double distance_estimate = std::abs(fx) / std::sqrt(g2);
            if (distance_estimate <= on_surface_tolerance()) return true;
            std::optional<Trial> best = backtrack(x, fx, capped((fx / g2) * g));
            const auto slow = [&] { return !best || std::abs(best->fx) > 0.25 * std::abs(fx); };
            if (slow()) {
                for (const Eigen::Vector3d& step : slow_progress_steps(x, fx, g)) {
                    const std::optional<Trial> trial = backtrack(x, fx, capped(step));
                    if (trial && (!best || std::abs(trial->fx) < std::abs(best->fx))) best = trial;
                }
            }
            if (!best) return distance_estimate <= stalled_on_surface_tolerance() || at_noise_level(fx, x, 64.0);
            if (slow()) {
                if (const std::optional<Eigen::Vector3d> root = bracketed_root(x, fx, best->step)) {
                    x = *root;
                    return true;
                }
            }
            const Eigen::Vector3d move = best->t * best->step;
            if (const std::optional<Eigen::Vector3d> root = first_crossing(x, fx, move)) {
                x = *root;
                return true;
            }
            x -= move;
        }
        const double fx = value(x);
        return at_noise_level(fx, x, 64.0) || std::abs(fx) <= stalled_on_surface_tolerance() * gradient(x).norm();
    }

    /// Fallback when stage 1 stalls at a critical point of F: march along rays from p in a fixed
    /// set of directions (a Fibonacci sphere) and bisect the nearest sign change of F.
    bool nearest_crossing_on_rays(Eigen::Vector3d& x) const {
        constexpr int directions = 128;
        constexpr int samples_per_ray = 256;
        const double reach = 2.0 * scale_;
        const double fp = value(p_);
        double nearest = std::numeric_limits<double>::infinity();
        std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> bracket;  // (same sign as p, opposite)
        double bracket_start_value = fp;
        const double golden_angle = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
        for (int d = 0; d < directions; ++d) {
            const double z = 1.0 - (2.0 * d + 1.0) / directions;
            const double radius = std::sqrt(1.0 - z * z);
            const Eigen::Vector3d direction(radius * std::cos(golden_angle * d), radius * std::sin(golden_angle * d), z);
            Eigen::Vector3d previous = p_;
            double previous_value = fp;
            for (int k = 1; k <= samples_per_ray; ++k) {
                const double distance = reach * k / samples_per_ray;
                if (distance >= nearest) break;
                const Eigen::Vector3d point = p_ + distance * direction;
                const double point_value = value(point);
                if (opposite_signs(previous_value, point_value) || point_value == 0.0) {
                    nearest = distance;
                    bracket = std::make_pair(previous, point);
                    bracket_start_value = previous_value;
                    break;
                }
                previous = point;
                previous_value = point_value;
            }
        }
        if (!bracket) return false;
        x = bisect(bracket->first, bracket_start_value, bracket->second);
        return true;
    }

    // --- stage 2: along the surface ------------------------------------------------------------

    /// Length of the component of p − ξ orthogonal to ∇F(ξ) (infinite where ∇F = 0).
    double tangential_residual(const Eigen::Vector3d& xi) const {
        const Eigen::Vector3d g = gradient(xi);
        const double g_norm = g.norm();
        if (!(g_norm > 0.0)) return std::numeric_limits<double>::infinity();
        const Eigen::Vector3d n = g / g_norm;
        const Eigen::Vector3d r = p_ - xi;
        return (r - r.dot(n) * n).norm();
    }

    void descend_distance(Eigen::Vector3d& xi) const {
        for (int iteration = 0; iteration < max_descent_iterations && !out_of_budget(); ++iteration) {
            const double residual = tangential_residual(xi);
            if (residual <= stop_tolerance()) return;
            if (!(try_reduced_newton_step(xi, residual) || try_tangential_step(xi))) return;
        }
    }

    /// |F(x)|/|∇F(x)|: how far x may be from F = 0, to first order.
    double surface_offset(const Eigen::Vector3d& x) const {
        const double g = gradient(x).norm();
        return g > 0.0 ? std::abs(value(x)) / g : 0.0;
    }

    /// Whether a candidate surface point is an improvement on ξ: clearly closer to p, or as
    /// close up to rounding with a much smaller tangential residual (the last Newton steps
    /// change the distance by less than its uncertainty, which includes how far each point may
    /// be from F = 0).
    bool improves(const Eigen::Vector3d& candidate, double candidate_residual, const Eigen::Vector3d& xi,
                  double residual) const {
        const double rounding = 1e-15 * scale_ + surface_offset(candidate) + surface_offset(xi);
        const double d_new = (p_ - candidate).norm();
        const double d_old = (p_ - xi).norm();
        return d_new < d_old - rounding || (d_new <= d_old + rounding && candidate_residual < 0.5 * residual);
    }

    /// Newton step for min |ξ − p|²/2 subject to F(ξ) = 0, in the tangent plane at ξ: gradient
    /// −Tᵀ(p − ξ), Hessian Tᵀ(I + μH)T with μ = (p − ξ)·∇F/|∇F|² (the Lagrange multiplier), and
    /// the Hessian's eigenvalues replaced by their absolute values so that the step always
    /// goes downhill, also near a saddle of the distance (points near the medial axis). The step
    /// is followed by stage 1, backtracked until it improves, and extended while it keeps
    /// getting closer where the Hessian had negative curvature.
    bool try_reduced_newton_step(Eigen::Vector3d& xi, double residual) const {
        const Eigen::Vector3d g = gradient(xi);
        const double g2 = g.squaredNorm();
        if (!(g2 > 0.0)) return false;
        const Eigen::Vector3d n = g / std::sqrt(g2);
        const Eigen::Vector3d r = p_ - xi;
        const double mu = r.dot(g) / g2;
        Eigen::Matrix<double, 3, 2> tangent;
        tangent.col(0) = n.unitOrthogonal();
        tangent.col(1) = n.cross(tangent.col(0));
        const Eigen::Matrix3d lagrangian_hessian = Eigen::Matrix3d::Identity() + mu * hessian(xi);
        const Eigen::Matrix2d reduced = tangent.transpose() * lagrangian_hessian * tangent;
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen;
        eigen.computeDirect(reduced);  // closed form for 2×2
        const Eigen::Vector2d lambda = eigen.eigenvalues();
        const double floor = 1e-10 * std::max(1.0, lambda.cwiseAbs().maxCoeff());
        const Eigen::Vector2d inverse = lambda.cwiseAbs().cwiseMax(floor).cwiseInverse();
        const Eigen::Matrix2d& v = eigen.eigenvectors();
        const Eigen::Vector3d step = tangent * (v * inverse.asDiagonal() * v.transpose() * (tangent.transpose() * r));
        if (!step.allFinite()) return false;
        const bool negative_curvature = lambda.minCoeff() < 0.0;

        for (double t = 1.0; t > 1e-7 && !out_of_budget(); t *= 0.5) {
            Eigen::Vector3d candidate = xi + t * step;
            if (!move_onto_surface(candidate, max_candidate_iterations)) continue;
            if (!improves(candidate, tangential_residual(candidate), xi, residual)) continue;
            if (t == 1.0 && negative_curvature) {
                for (double longer = 2.0; longer <= 64.0 && !out_of_budget(); longer *= 2.0) {
                    Eigen::Vector3d further = xi + longer * step;
                    if (!move_onto_surface(further, max_candidate_iterations) ||
                        !((p_ - further).norm() < (p_ - candidate).norm()))
                        break;
                    candidate = further;
                }
            }
            xi = candidate;
            return true;
        }
        return false;
    }

    /// Step along the tangential part of p − ξ: halved until ξ gets closer to p, or doubled
    /// while that keeps getting closer (to leave a saddle of the distance quickly).
    bool try_tangential_step(Eigen::Vector3d& xi) const {
        const Eigen::Vector3d g = gradient(xi);
        const Eigen::Vector3d r = p_ - xi;
        // At a singular point (∇F = 0) every direction is tangential: aim straight at p.
        const Eigen::Vector3d tangential =
            g.squaredNorm() > 0.0 ? Eigen::Vector3d(r - (r.dot(g) / g.squaredNorm()) * g) : r;
        auto closer_point = [&](double t, double than) -> std::optional<Eigen::Vector3d> {
            Eigen::Vector3d candidate = xi + t * tangential;
            if (move_onto_surface(candidate, max_candidate_iterations) && (p_ - candidate).norm() < than)
                return candidate;
            return std::nullopt;
        };
        for (double t = 1.0; t > 1e-7 && !out_of_budget(); t *= 0.5) {
            std::optional<Eigen::Vector3d> accepted = closer_point(t, r.norm());
            if (!accepted) continue;
            if (t == 1.0) {
                for (double longer = 2.0; longer <= 64.0 && !out_of_budget(); longer *= 2.0) {
                    const std::optional<Eigen::Vector3d> further = closer_point(longer, (p_ - *accepted).norm());
                    if (!further) break;
                    accepted = further;
                }
            }
            xi = *accepted;
            return true;
        }
        return false;
    }

    [[noreturn]] void fail(const std::string& problem) const {
        throw Error("closest_point: " + problem + " " + format_point(p_) + " for F = " + f_.to_string());
    }

    const Polynomial& f_;
    const Polynomial abs_f_;  ///< F with every coefficient replaced by its absolute value
    const Eigen::Vector3d p_;
    const double scale_;
    mutable long evaluations_ = 0;
};

}  // namespace

// ---------------------------------------------------------------------------------------------

std::vector<std::string> named_shape_names() {
    std::vector<std::string> names;
    for (const NamedShape& shape : named_shapes()) names.emplace_back(shape.name);
    return names;
}

ImplicitShape make_shape(const std::string& name_or_polynomial, double default_box) {
    if (const NamedShape* named = find_named_shape(name_or_polynomial)) {
        return ImplicitShape{named->name, Polynomial::parse(named->formula), named->lower, named->upper,
                             named->clipped};
    }
    if (!std::isfinite(default_box) || default_box <= 0.0)
        throw Error("make_shape: the default box half-size must be a finite positive number (got " +
                    std::to_string(default_box) + ")");
    Polynomial polynomial;
    try {
        polynomial = Polynomial::parse(name_or_polynomial);
    } catch (const Error& error) {
        throw Error("'" + name_or_polynomial + "' is neither a named shape (" + joined_shape_names() +
                    ") nor a valid polynomial: " + error.what());
    }
    const Eigen::Vector3d half = Eigen::Vector3d::Constant(default_box);
    return ImplicitShape{name_or_polynomial, std::move(polynomial), -half, half, {true, true, true}};
}

ImplicitShape make_plane_shape(const Eigen::Vector3d& normal, double offset, double half_size) {
    const double length = normal.norm();
    if (!normal.allFinite() || !(length > 0.0)) throw Error("make_plane_shape: the normal must be a finite non-zero vector");
    if (!std::isfinite(offset)) throw Error("make_plane_shape: the offset must be finite");
    if (!std::isfinite(half_size) || half_size <= 0.0)
        throw Error("make_plane_shape: the box half-size must be a finite positive number");
    const Eigen::Vector3d n = normal / length;
    Polynomial polynomial = Polynomial::from_monomials(
        {{n.x(), 1, 0, 0}, {n.y(), 0, 1, 0}, {n.z(), 0, 0, 1}, {-offset, 0, 0, 0}});
    const Eigen::Vector3d half = Eigen::Vector3d::Constant(half_size);
    return ImplicitShape{"plane " + polynomial.to_string(), std::move(polynomial), -half, half, {true, true, true}};
}

namespace {

/// The checked grid of a digitization (at most 2^34 voxels).
DigitizationGrid checked_digitization_grid(const ImplicitShape& shape, double h) {
    check_digitization_input(shape, h);
    DigitizationGrid grid(shape, h);
    constexpr double max_voxels = 17179869184.0;  // 2^34
    const double voxels = grid.voxel_count();
    if (voxels > max_voxels) {
        std::ostringstream message;
        message << "digitize: shape '" << shape.name << "' at h = " << h << " needs a " << grid.range(0).count
                << " x " << grid.range(1).count << " x " << grid.range(2).count << " grid (" << voxels
                << " voxels), more than the limit of 2^34; use a larger h";
        throw Error(message.str());
    }
    return grid;
}

/// The voxels of the grid's box, slice by slice in parallel.
BinaryVolume digitize_grid(DigitizationGrid& grid) {
    const VoxelBox& box = grid.box();
    BinaryVolume volume;
    volume.grid = grid.voxel_grid();
    volume.grid.origin = volume.grid.voxel_center(box.lo[0], box.lo[1], box.lo[2]);
    volume.grid.dims = box.size();
    const double voxels = double(box.voxel_count());
    try {
        volume.mask.assign(static_cast<std::size_t>(voxels), 0);
        grid.prepare_columns();
    } catch (const std::bad_alloc&) {
        throw Error("digitize: not enough memory for a grid of " + std::to_string(static_cast<long long>(voxels)) +
                    " voxels");
    }
    const std::size_t slice_size = static_cast<std::size_t>(box.size()[0] * box.size()[1]);
#pragma omp parallel
    {
        std::vector<double> row_sum(static_cast<std::size_t>(box.size()[0]));
#pragma omp for schedule(dynamic)
        for (std::int64_t k = box.lo[2]; k < box.hi[2]; ++k)
            grid.digitize_slice(k, volume.mask.data() + static_cast<std::size_t>(k - box.lo[2]) * slice_size, row_sum);
    }
    return volume;
}

}  // namespace

BinaryVolume digitize(const ImplicitShape& shape, double h) {
    DigitizationGrid grid = checked_digitization_grid(shape, h);
    return digitize_grid(grid);
}

VoxelGrid digitization_grid(const ImplicitShape& shape, double h) { return checked_digitization_grid(shape, h).voxel_grid(); }

BinaryVolume digitize_box(const ImplicitShape& shape, double h, const VoxelBox& box) {
    DigitizationGrid grid = checked_digitization_grid(shape, h);
    const VoxelGrid whole = grid.voxel_grid();
    if (box.empty() || !VoxelBox{{0, 0, 0}, whole.dims}.contains(box))
        throw Error("digitize: the box of voxels is empty or not inside the " + std::to_string(whole.dims[0]) + " x " +
                    std::to_string(whole.dims[1]) + " x " + std::to_string(whole.dims[2]) + " grid");
    grid.restrict_to(box);
    return digitize_grid(grid);
}

Eigen::Vector3d true_normal(const ImplicitShape& shape, const Eigen::Vector3d& p) {
    const Eigen::Vector3d g = shape.polynomial.gradient(p);
    const double length = g.norm();
    if (!(length > 0.0) || !std::isfinite(length))
        throw Error("true_normal: the gradient of '" + shape.name + "' vanishes at " + format_point(p) +
                    " (a singular point)");
    return g / length;
}

Eigen::Vector3d closest_point(const ImplicitShape& shape, const Eigen::Vector3d& p) {
    if (!p.allFinite()) throw Error("closest_point: the point " + format_point(p) + " is not finite");
    const Polynomial& f = shape.polynomial;
    if (f.degree() == 0)
        throw Error("closest_point: '" + shape.name + "' is constant, so F = 0 is not a surface");
    if (f.degree() == 1) return closest_point_on_plane(f, p);
    if (const std::optional<SphereForm> sphere = as_sphere(f)) return closest_point_on_sphere(*sphere, p);
    return ClosestPointSearch(shape, p).run();
}

}  // namespace dsreg
