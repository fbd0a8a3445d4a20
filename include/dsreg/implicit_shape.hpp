// dsreg — implicit shapes: polynomials in x, y, z, the named shapes of the digital-geometry
// community, their Gauss digitization, true normals and closest-point projection.
//
// A shape is the set F(x,y,z) ≤ 0 in physical coordinates, intersected with the shape's box.
// Gauss digitization at grid step h: voxel (i,j,k) is inside iff F(h·i, h·j, h·k) ≤ 0 and
// (h·i, h·j, h·k) lies in the box; the grid has spacing (h,h,h) and origin h·(index of voxel
// (0,0,0)) — see volume.hpp. For a bounded shape the box contains {F ≤ 0} and the box test
// changes nothing; for a shape clipped by its box (see ImplicitShape::clipped) the box faces
// become part of the digitized object's boundary.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "dsreg/volume.hpp"

namespace dsreg {

/// A polynomial in x, y, z parsed from a string such as "x^2+y^2+z^2-81" or
/// "-1*(8-0.03*x^4+2*x^2)". Grammar (whitespace allowed between tokens):
///
///   sum     := product (('+' | '-') product)*
///   product := signed ('*' signed)*
///   signed  := ('+' | '-') signed | power          (so -x^2 = -(x^2))
///   power   := primary ('^' integer)?              (a^b^c is rejected: use parentheses)
///   primary := number | 'x' | 'y' | 'z' | '(' sum ')'
///
/// Numbers: 123, 1.5, .5, 1e-3, 2.5E+4. Exponents: non-negative integer literals ≤ 64.
/// Multiplication must be written: "2x" and "x y" are errors (no implicit multiplication).
/// The polynomial is stored expanded: like terms combined, zero coefficients dropped.
/// The total degree is capped at max_degree (every intermediate product too), so a string
/// such as "(x+y+z)^1000000" fails fast with a clear error instead of exhausting memory.
class Polynomial {
public:
    static constexpr int max_degree = 64;

    struct Monomial {
        double coefficient;
        int ex, ey, ez;
    };

    /// The zero polynomial.
    Polynomial() = default;

    /// Throws dsreg::Error naming the problem and its position (0-based character index)
    /// on a malformed string, e.g. "polynomial 'x^2+*y': unexpected '*' at position 4".
    static Polynomial parse(const std::string& text);

    /// Builds a polynomial from monomials (in any order, possibly repeated: like terms are
    /// combined). Throws dsreg::Error on a negative exponent, a degree above max_degree or a
    /// non-finite coefficient.
    static Polynomial from_monomials(std::vector<Monomial> monomials);

    /// F(p). No allocation; the exact arithmetic (and so the exact result) is the one digitize()
    /// uses, so digitize(...) agrees bit for bit with value() at the voxel centres h·(i,j,k).
    double value(const Eigen::Vector3d& p) const;
    Eigen::Vector3d gradient(const Eigen::Vector3d& p) const;
    Eigen::Matrix3d hessian(const Eigen::Vector3d& p) const;
    /// Total degree; 0 for constants, including the zero polynomial.
    int degree() const { return degree_; }
    /// Highest exponent of x (axis 0), y (axis 1) or z (axis 2).
    int max_exponent(int axis) const { return max_exponent_[axis]; }

    /// Canonical order: decreasing total degree, then decreasing (ex, ey, ez).
    const std::vector<Monomial>& monomials() const { return monomials_; }

    /// A string that parse() maps back to this exact polynomial (each coefficient in the
    /// shortest decimal form that reads back to the same double), e.g. "3*x^2 - 2*x*y + 1".
    std::string to_string() const;

private:
    explicit Polynomial(std::vector<Monomial> canonical_monomials);

    std::vector<Monomial> monomials_;
    int degree_ = 0;
    std::array<int, 3> max_exponent_{0, 0, 0};
};

/// An implicit shape F ≤ 0, with an axis-aligned box that contains it or clips it.
struct ImplicitShape {
    std::string name;        ///< named shape or the polynomial text
    Polynomial polynomial;
    Eigen::Vector3d lower;   ///< box, physical units
    Eigen::Vector3d upper;
    /// clipped[a] is false when {F ≤ 0} is proven to lie within [lower[a], upper[a]] along axis a
    /// (F > 0 on and beyond both box faces orthogonal to a). When true, {F ≤ 0} may extend
    /// beyond the box along a: the shape is cut by those box faces, the digitized object has
    /// flat faces there, and points on them are not near F = 0 (leave them out of
    /// ground-truth comparisons). Polynomial strings given by the user are clipped on all axes.
    std::array<bool, 3> clipped{true, true, true};
};

/// Names of the built-in shapes (sphere1, sphere9, ellipsoid, cylinder, torus, rcube, goursat,
/// goursat-hole, distel, leopold, diabolo, heart, crixxi), with the polynomial strings of
/// DESIGN.md. Boxes: see implicit_shape.cpp. Note that, with F ≤ 0 inside, "distel", "heart" and
/// "crixxi" as written by the community are the unbounded complements of a bounded solid: their
/// box is a clip box, so each digitizes as a box with a cavity of that shape.
std::vector<std::string> named_shape_names();

/// A named shape, or any polynomial string (then the box is [-default_box, default_box] on each
/// axis, clipped on all axes). Throws dsreg::Error for an unknown name / bad polynomial, or a
/// default_box that is not finite and positive.
ImplicitShape make_shape(const std::string& name_or_polynomial, double default_box = 10.0);

/// The half-space n·p ≤ offset for a unit vector n = normal/|normal| (so `offset` is the signed
/// distance from the origin to the plane), clipped by the box [-half_size, half_size]³. With a
/// normal not aligned with an axis, its digitization is a tilted digital plane (the convergence
/// experiment of the paper, Fig. 7). Throws dsreg::Error for a zero or non-finite normal, a
/// non-finite offset or half_size ≤ 0.
ImplicitShape make_plane_shape(const Eigen::Vector3d& normal, double offset, double half_size);

/// Gauss digitization at step h > 0 over the shape's box, one voxel of margin on each side:
/// i runs from floor(lower.x/h)−1 to ceil(upper.x/h)+1 (likewise j, k); spacing (h,h,h);
/// origin = h·(i_min, j_min, k_min). Voxel (i,j,k) is inside iff F(h·i, h·j, h·k) ≤ 0 and that
/// point lies in the box, so the margin is always background. Parallel over z slices (OpenMP).
/// Throws dsreg::Error for h ≤ 0 or non-finite, an invalid box, or more than 2^34 voxels.
BinaryVolume digitize(const ImplicitShape& shape, double h);

/// The grid of digitize(shape, h) (dims, spacing, origin), without digitizing. Same checks.
VoxelGrid digitization_grid(const ImplicitShape& shape, double h);

/// The voxels of `box` (non-empty, inside the grid of digitize(shape, h)) of that digitization,
/// bit for bit, with memory for the box alone: grid.dims = box.size(), origin = the centre of
/// the box's first voxel. Throws dsreg::Error as digitize does, or for a box outside the grid.
BinaryVolume digitize_box(const ImplicitShape& shape, double h, const VoxelBox& box);

/// Unit outward normal ∇F/|∇F| at p. Throws dsreg::Error where ∇F = 0 (singular point).
Eigen::Vector3d true_normal(const ImplicitShape& shape, const Eigen::Vector3d& p);

/// Closest point ξ(p) of {F = 0} to p: a point with F(ξ) = 0 (to rounding) and p − ξ parallel
/// to ∇F(ξ), reached from the gradient-Newton projection of p by steps that always bring ξ
/// closer to p. So ξ is the closest point at least locally; for points near the surface (well
/// within its reach, e.g. digital-surface vertices) the search starts next to the foot point
/// and ξ is the closest point. At a singular point of the surface (∇F = 0, e.g. the heart's
/// bottom tip) ξ is a local minimum of the distance and the parallel condition is void, and
/// F = 0 is located only to about (rounding error of F)^(1/multiplicity). Exact formulas for
/// planes (degree 1) and spheres a·|p|² + b·p + c. Ignores the box. A few µs per call near a
/// regular surface; a bounded amount of work (≈ 50000 evaluations of F) in the worst case.
/// Throws dsreg::Error if F = 0 is empty (constant F, imaginary sphere) or not found.
Eigen::Vector3d closest_point(const ImplicitShape& shape, const Eigen::Vector3d& p);

}  // namespace dsreg
