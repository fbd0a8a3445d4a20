// dsreg — implicit shapes: polynomials in x, y, z, the named shapes of the digital-geometry
// community, their Gauss digitization, true normals and closest-point projection.
//
// A shape is the set F(x,y,z) ≤ 0 in physical coordinates. Gauss digitization at grid step h:
// voxel (i,j,k) is inside iff F(h·i, h·j, h·k) ≤ 0; the grid has spacing (h,h,h) and origin
// h·(index of voxel (0,0,0)) — see volume.hpp.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "dsreg/volume.hpp"

namespace dsreg {

/// A polynomial in x, y, z parsed from a string such as "x^2+y^2+z^2-81" or
/// "-1*(8-0.03*x^4+2*x^2)". Grammar: numbers (123, 1.5, 1e-3), variables x y z, + - * ^
/// (non-negative integer exponents), unary minus, parentheses. Stored in expanded monomial form.
class Polynomial {
public:
    /// Throws dsreg::Error with the position and the problem on a malformed string.
    static Polynomial parse(const std::string& text);

    double value(const Eigen::Vector3d& p) const;
    Eigen::Vector3d gradient(const Eigen::Vector3d& p) const;
    Eigen::Matrix3d hessian(const Eigen::Vector3d& p) const;
    int degree() const;

    struct Monomial {
        double coefficient;
        int ex, ey, ez;
    };
    const std::vector<Monomial>& monomials() const { return monomials_; }

private:
    std::vector<Monomial> monomials_;
};

/// An implicit shape F ≤ 0, with an axis-aligned box known to contain it.
struct ImplicitShape {
    std::string name;        ///< named shape or the polynomial text
    Polynomial polynomial;
    Eigen::Vector3d lower;   ///< bounding box of {F ≤ 0}, physical units
    Eigen::Vector3d upper;
};

/// Names of the built-in shapes (sphere1, sphere9, ellipsoid, cylinder, torus, rcube, goursat,
/// goursat-hole, distel, leopold, diabolo, heart, crixxi).
std::vector<std::string> named_shape_names();

/// A named shape, or any polynomial string (then the bounding box is `default_box` on each
/// axis: [-default_box, default_box]). Throws dsreg::Error for an unknown name / bad polynomial.
ImplicitShape make_shape(const std::string& name_or_polynomial, double default_box = 10.0);

/// Gauss digitization at step h > 0 over the shape's box (one voxel of margin on each side).
BinaryVolume digitize(const ImplicitShape& shape, double h);

/// Unit outward normal ∇F/|∇F| at p.
Eigen::Vector3d true_normal(const ImplicitShape& shape, const Eigen::Vector3d& p);

/// Closest point ξ(p) of {F = 0} to p (robust Newton projection).
Eigen::Vector3d closest_point(const ImplicitShape& shape, const Eigen::Vector3d& p);

}  // namespace dsreg
