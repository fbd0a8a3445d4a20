// Tests of the implicit-shape module: polynomial parsing and evaluation, named shapes and their
// boxes, Gauss digitization, true normals and closest-point projection.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "dsreg/error.hpp"
#include "dsreg/implicit_shape.hpp"

namespace dsreg {
namespace {

using Vec3 = Eigen::Vector3d;
using Formula = std::function<double(double, double, double)>;

constexpr double pi = 3.14159265358979323846;

double sq(double v) { return v * v; }
double cube(double v) { return v * v * v; }

/// Uniform random point in the box [lower, upper].
Vec3 random_point(std::mt19937_64& rng, const Vec3& lower, const Vec3& upper) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    return Vec3(lower.x() + unit(rng) * (upper.x() - lower.x()), lower.y() + unit(rng) * (upper.y() - lower.y()),
                lower.z() + unit(rng) * (upper.z() - lower.z()));
}

Vec3 random_unit_vector(std::mt19937_64& rng) {
    std::normal_distribution<double> normal(0.0, 1.0);
    Vec3 v;
    do {
        v = Vec3(normal(rng), normal(rng), normal(rng));
    } while (v.norm() < 1e-3);
    return v.normalized();
}

/// Absolute size of the terms of F at p: a scale for the rounding error of F(p).
double term_magnitude(const Polynomial& f, const Vec3& p) {
    double sum = 0.0;
    for (const Polynomial::Monomial& m : f.monomials())
        sum += std::abs(m.coefficient) * std::pow(std::abs(p.x()), m.ex) * std::pow(std::abs(p.y()), m.ey) *
               std::pow(std::abs(p.z()), m.ez);
    return sum;
}

/// Expects `action` to throw dsreg::Error whose message contains `fragment`.
template <typename Action>
void expect_error_containing(Action action, const std::string& fragment, const std::string& context) {
    try {
        action();
        ADD_FAILURE() << context << ": expected dsreg::Error containing \"" << fragment << "\"";
    } catch (const Error& error) {
        EXPECT_NE(std::string(error.what()).find(fragment), std::string::npos)
            << context << ": message \"" << error.what() << "\" lacks \"" << fragment << "\"";
    }
}

// The formulas of DESIGN.md, written out by hand.
struct NamedFormula {
    std::string name;
    Formula formula;
};

std::vector<NamedFormula> hand_written_named_shapes() {
    return {
        {"sphere1", [](double x, double y, double z) { return x * x + y * y + z * z - 1; }},
        {"sphere9", [](double x, double y, double z) { return x * x + y * y + z * z - 81; }},
        {"ellipsoid", [](double x, double y, double z) { return 3 * x * x + 2 * y * y + z * z - 90; }},
        {"cylinder", [](double x, double, double z) { return x * x + 2 * z * z - 90; }},
        {"torus",
         [](double x, double y, double z) { return sq(x * x + y * y + z * z + 36 - 4) - 4 * 36 * (x * x + y * y); }},
        {"rcube", [](double x, double y, double z) { return sq(x * x) + sq(y * y) + sq(z * z) - 6561; }},
        {"goursat",
         [](double x, double y, double z) {
             return -(8 - 0.03 * sq(x * x) - 0.03 * sq(y * y) - 0.03 * sq(z * z) + 2 * x * x + 2 * y * y + 2 * z * z);
         }},
        {"goursat-hole",
         [](double x, double y, double z) {
             return sq(x * x) + sq(y * y) + sq(z * z) - 8 * (x * x + y * y + z * z) + 32 - 2;
         }},
        {"distel",
         [](double x, double y, double z) {
             return 10000 - (x * x + y * y + z * z + 1000 * (x * x + y * y) * (x * x + z * z) * (y * y + z * z));
         }},
        {"leopold",
         [](double x, double y, double z) { return x * x * y * y * z * z + 4 * x * x + 4 * y * y + 3 * z * z - 100; }},
        {"diabolo", [](double x, double y, double z) { return x * x - sq(y * y + z * z); }},
        {"heart",
         [](double x, double y, double z) {
             return -cube(x * x + 2.25 * y * y + z * z - 1) + x * x * cube(z) + 0.1125 * y * y * cube(z);
         }},
        {"crixxi",
         [](double x, double y, double z) { return -0.9 * sq(y * y + z * z - 1) - cube(x * x + y * y - 1); }},
    };
}

// ---------------------------------------------------------------------------------------------
// Polynomial parsing and evaluation

TEST(Polynomial, ValuesMatchDirectEvaluation) {
    const std::vector<std::pair<std::string, Formula>> cases = {
        {"3*x^2 - 2*x*y + z - 7", [](double x, double y, double z) { return 3 * x * x - 2 * x * y + z - 7; }},
        {"(x+1)^3", [](double x, double, double) { return cube(x + 1); }},
        {"-(x-y)^2*2 + 1e-3*z", [](double x, double y, double z) { return -sq(x - y) * 2 + 1e-3 * z; }},
        {"-x^2", [](double x, double, double) { return -(x * x); }},
        {"2*-x", [](double x, double, double) { return -2 * x; }},
        {"- -x + +y", [](double x, double y, double) { return x + y; }},
        {"x-y-z", [](double x, double y, double z) { return x - y - z; }},
        {" x * ( y + z ) ", [](double x, double y, double z) { return x * (y + z); }},
        {".5*x + 1.5e2*y*z + 2.5E+1", [](double x, double y, double z) { return 0.5 * x + 150 * y * z + 25; }},
        {"(x^2+y^2)^2 - z", [](double x, double y, double z) { return sq(x * x + y * y) - z; }},
        {"2^3*x^0 + y^1", [](double, double y, double) { return 8 + y; }},
        {"((x))*(((y)))*z", [](double x, double y, double z) { return x * y * z; }},
        {"(x+y+z)^5", [](double x, double y, double z) { return std::pow(x + y + z, 5); }},
        {"(x - 2*y)*(3*z + x)*(y - 1)", [](double x, double y, double z) { return (x - 2 * y) * (3 * z + x) * (y - 1); }},
        {"\tx\n+\ry", [](double x, double y, double) { return x + y; }},
    };
    std::mt19937_64 rng(12345);
    for (const auto& [text, formula] : cases) {
        const Polynomial f = Polynomial::parse(text);
        for (int sample = 0; sample < 50; ++sample) {
            const Vec3 p = random_point(rng, Vec3::Constant(-3.0), Vec3::Constant(3.0));
            const double expected = formula(p.x(), p.y(), p.z());
            EXPECT_NEAR(f.value(p), expected, 1e-12 * (1.0 + term_magnitude(f, p))) << text << " at " << p.transpose();
        }
    }
}

TEST(Polynomial, NamedShapeStringsEvaluateAsTheirFormulas) {
    const std::vector<NamedFormula> formulas = hand_written_named_shapes();
    std::vector<std::string> expected_names;
    for (const NamedFormula& entry : formulas) expected_names.push_back(entry.name);
    EXPECT_EQ(named_shape_names(), expected_names);

    std::mt19937_64 rng(7);
    for (const NamedFormula& entry : formulas) {
        const ImplicitShape shape = make_shape(entry.name);
        EXPECT_EQ(shape.name, entry.name);
        for (int sample = 0; sample < 200; ++sample) {
            const Vec3 p = random_point(rng, shape.lower, shape.upper);
            const double expected = entry.formula(p.x(), p.y(), p.z());
            EXPECT_NEAR(shape.polynomial.value(p), expected, 1e-12 * (1.0 + term_magnitude(shape.polynomial, p)))
                << entry.name << " at " << p.transpose();
        }
    }
}

TEST(Polynomial, GradientAndHessianMatchCentralDifferences) {
    std::vector<Polynomial> polynomials;
    for (const std::string& name : named_shape_names()) polynomials.push_back(make_shape(name).polynomial);
    polynomials.push_back(Polynomial::parse("x*y^2*z^3 - 2*x^3*z + y - 5"));
    polynomials.push_back(Polynomial::parse("(x - y + 2*z)^4 - x*y*z"));

    std::mt19937_64 rng(99);
    for (const Polynomial& f : polynomials) {
        for (int sample = 0; sample < 30; ++sample) {
            const Vec3 p = random_point(rng, Vec3::Constant(-2.5), Vec3::Constant(2.5));
            const double step = 1e-5;
            const Vec3 g = f.gradient(p);
            const Eigen::Matrix3d h = f.hessian(p);
            EXPECT_TRUE(h.isApprox(h.transpose()));
            for (int a = 0; a < 3; ++a) {
                const Vec3 e = step * Vec3::Unit(a);
                const double dfa = (f.value(p + e) - f.value(p - e)) / (2 * step);
                EXPECT_NEAR(g[a], dfa, 1e-6 * (1.0 + g.cwiseAbs().maxCoeff() + term_magnitude(f, p)))
                    << f.to_string() << " d/d" << a << " at " << p.transpose();
                const Vec3 dga = (f.gradient(p + e) - f.gradient(p - e)) / (2 * step);
                for (int b = 0; b < 3; ++b)
                    EXPECT_NEAR(h(b, a), dga[b], 1e-6 * (1.0 + h.cwiseAbs().maxCoeff() + g.cwiseAbs().maxCoeff()))
                        << f.to_string() << " d2/d" << a << "d" << b << " at " << p.transpose();
            }
        }
    }
}

TEST(Polynomial, ExpandsToCanonicalMonomials) {
    const Polynomial twice = Polynomial::parse("x + x");
    ASSERT_EQ(twice.monomials().size(), 1u);
    EXPECT_EQ(twice.monomials()[0].coefficient, 2.0);

    const Polynomial zero = Polynomial::parse("x*y - y*x");
    EXPECT_TRUE(zero.monomials().empty());
    EXPECT_EQ(zero.degree(), 0);
    EXPECT_EQ(zero.value(Vec3(1.0, 2.0, 3.0)), 0.0);

    const Polynomial one = Polynomial::parse("(x+1)^2 - x^2 - 2*x");
    ASSERT_EQ(one.monomials().size(), 1u);
    EXPECT_EQ(one.monomials()[0].coefficient, 1.0);
    EXPECT_EQ(one.degree(), 0);

    // (x+y+z)^3 has one monomial per exponent triple of sum 3: C(5,2) = 10.
    const Polynomial trinomial = Polynomial::parse("(x+y+z)^3");
    EXPECT_EQ(trinomial.monomials().size(), 10u);
    EXPECT_EQ(trinomial.degree(), 3);

    EXPECT_EQ(make_shape("torus").polynomial.degree(), 4);
    EXPECT_EQ(make_shape("distel").polynomial.degree(), 6);
    EXPECT_EQ(make_shape("heart").polynomial.degree(), 6);
    EXPECT_EQ(make_shape("leopold").polynomial.max_exponent(2), 2);

    // Canonical order: decreasing total degree, then decreasing exponents; no repeats, no zeros.
    for (const std::string& name : named_shape_names()) {
        const ImplicitShape shape = make_shape(name);
        const auto& monomials = shape.polynomial.monomials();
        for (std::size_t m = 0; m < monomials.size(); ++m) {
            EXPECT_NE(monomials[m].coefficient, 0.0);
            if (m == 0) continue;
            const auto& a = monomials[m - 1];
            const auto& b = monomials[m];
            const std::array<int, 4> ka{a.ex + a.ey + a.ez, a.ex, a.ey, a.ez};
            const std::array<int, 4> kb{b.ex + b.ey + b.ez, b.ex, b.ey, b.ez};
            EXPECT_GT(ka, kb) << name;
        }
    }
}

TEST(Polynomial, ToStringRoundTripsExactly) {
    std::vector<Polynomial> polynomials;
    for (const std::string& name : named_shape_names()) polynomials.push_back(make_shape(name).polynomial);
    polynomials.push_back(Polynomial::parse("0.1*x - 1e-7*y^3*z + 123456.789"));
    polynomials.push_back(Polynomial::parse("0"));
    // 43 680 terms of degree up to 61 (the fuzzer's find): its written form is a long sum of
    // single monomials, whose products must not cost a dense array each.
    polynomials.push_back(Polynomial::parse("(x + 641+y+z)^61"));
    for (const Polynomial& f : polynomials) {
        const Polynomial g = Polynomial::parse(f.to_string());
        ASSERT_EQ(g.monomials().size(), f.monomials().size()) << f.to_string();
        for (std::size_t m = 0; m < f.monomials().size(); ++m) {
            EXPECT_EQ(g.monomials()[m].coefficient, f.monomials()[m].coefficient) << f.to_string();
            EXPECT_EQ(g.monomials()[m].ex, f.monomials()[m].ex);
            EXPECT_EQ(g.monomials()[m].ey, f.monomials()[m].ey);
            EXPECT_EQ(g.monomials()[m].ez, f.monomials()[m].ez);
        }
    }
}

TEST(Polynomial, FromMonomialsCombinesAndValidates) {
    const Polynomial f = Polynomial::from_monomials({{1.0, 1, 0, 0}, {2.0, 0, 0, 0}, {3.0, 1, 0, 0}, {0.0, 0, 5, 0}});
    ASSERT_EQ(f.monomials().size(), 2u);
    EXPECT_EQ(f.value(Vec3(2.0, 7.0, 7.0)), 10.0);
    EXPECT_THROW(Polynomial::from_monomials({{1.0, -1, 0, 0}}), Error);
    EXPECT_THROW(Polynomial::from_monomials({{1.0, 30, 30, 30}}), Error);
    EXPECT_THROW(Polynomial::from_monomials({{std::numeric_limits<double>::infinity(), 0, 0, 0}}), Error);
}

TEST(Polynomial, RejectsMalformedStrings) {
    // Implicit multiplication ("2x") is rejected: every named shape writes '*' explicitly, and
    // accepting it would make "2e3" / "2e" ambiguous. Each case: text, expected message fragment.
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"x^", "exponent after '^' but the text ends at position 2"},
        {"(x+1", "unclosed '(' at position 0"},
        {"x**2", "unexpected '*'"},
        {"2x", "missing operator before 'x'"},
        {"x^-1", "non-negative integer"},
        {"x^1.5", "non-negative integer"},
        {"x^y", "non-negative integer"},
        {"", "empty expression"},
        {"   ", "empty expression"},
        {"w+1", "unknown variable 'w'"},
        {"x^2+*y", "unexpected '*' at position 4"},
        {"x+", "the text ends"},
        {"()", "empty parentheses"},
        {"x)", "unmatched ')'"},
        {"1e", "exponent digits missing"},
        {"1e+", "exponent digits missing"},
        {".", "at least one digit"},
        {"x y", "missing operator before 'y' (implicit multiplication is not supported: write 2*x) at position 2"},
        {"x^2^3", "chained '^'"},
        {"x # 2", "unexpected '#'"},
        {"x+\x01", "unexpected byte 0x01"},
        {"1e999*x", "out of range"},
        {"(1e200*x)^2", "overflows"},
    };
    for (const auto& [text, fragment] : cases) {
        expect_error_containing([&] { Polynomial::parse(text); }, fragment, "'" + text + "'");
        expect_error_containing([&] { Polynomial::parse(text); }, "polynomial '", "'" + text + "'");
    }
}

TEST(Polynomial, CapsDegreeExponentAndNesting) {
    const auto start = std::chrono::steady_clock::now();
    expect_error_containing([] { Polynomial::parse("(x+y+z)^1000000"); }, "exponent 1000000 exceeds the maximum 64",
                            "huge exponent");
    expect_error_containing([] { Polynomial::parse("(x+y+z)^99999999999999999999999"); }, "exceeds the maximum",
                            "exponent overflowing an integer");
    expect_error_containing([] { Polynomial::parse("(x+y)^40*(x+y)^30"); }, "degree 70 exceeds the maximum 64 at position 8",
                            "product degree");
    expect_error_containing([] { Polynomial::parse("(x*y)^33"); }, "degree 66", "power degree");
    expect_error_containing([] { Polynomial::parse(std::string(100000, '(') + "x" + std::string(100000, ')')); },
                            "nesting deeper", "deep parentheses");
    expect_error_containing([] { Polynomial::parse(std::string(100000, '-') + "x"); }, "nesting deeper",
                            "many unary minus");
    // Long strings whose expansion is quadratic or worse in their length are stopped too.
    std::string long_product = "(1+x+y+z)^32";  // 6545 terms, each "*1" touches them all
    for (int factor = 0; factor < 20000; ++factor) long_product += "*1";
    expect_error_containing([&] { Polynomial::parse(long_product); }, "too much work", "long product");
    std::string long_sum = "(1+x+y+z)^32";
    for (int term = 0; term < 100000; ++term) long_sum += "+x";
    EXPECT_EQ(Polynomial::parse(long_sum).monomials().size(), 6545u);  // a long sum stays linear
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LT(seconds, 30.0) << "abusive strings must be rejected, not expanded for ever";

    // The cap itself is usable: (1+x+y+z)^64 has every monomial of degree ≤ 64, C(67,3) of them.
    const Polynomial big = Polynomial::parse("(1+x+y+z)^64");
    EXPECT_EQ(big.degree(), 64);
    EXPECT_EQ(big.monomials().size(), 47905u);
    EXPECT_NEAR(big.value(Vec3(1.0, 1.0, 1.0)) / std::pow(4.0, 64), 1.0, 1e-12);
    // Expanded, the value suffers cancellation: the error scales with Σ|terms| = 1.35^64 ≈ 2e8.
    const Vec3 q(0.1, -0.2, 0.05);
    EXPECT_NEAR(big.value(q), std::pow(0.95, 64), 1e-14 * term_magnitude(big, q));
}

// ---------------------------------------------------------------------------------------------
// Named shapes and their boxes

/// Points of the face {p[axis] = value} of the box, on an n×n grid.
std::vector<Vec3> face_samples(const ImplicitShape& shape, int axis, double value, int n) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    std::vector<Vec3> points;
    for (int a = 0; a <= n; ++a) {
        for (int b = 0; b <= n; ++b) {
            Vec3 p;
            p[axis] = value;
            p[u] = shape.lower[u] + (shape.upper[u] - shape.lower[u]) * a / n;
            p[v] = shape.lower[v] + (shape.upper[v] - shape.lower[v]) * b / n;
            points.push_back(p);
        }
    }
    return points;
}

bool has_point_with_negative_value(const ImplicitShape& shape, int n) {
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j)
            for (int k = 0; k <= n; ++k) {
                const Vec3 t(double(i) / n, double(j) / n, double(k) / n);
                const Vec3 p = shape.lower + t.cwiseProduct(shape.upper - shape.lower);
                if (shape.polynomial.value(p) < 0.0) return true;
            }
    return false;
}

TEST(NamedShapes, BoxesContainTheShapeAlongEveryUnclippedAxis) {
    std::mt19937_64 rng(2024);
    for (const std::string& name : named_shape_names()) {
        const ImplicitShape shape = make_shape(name);
        ASSERT_TRUE((shape.lower.array() < shape.upper.array()).all()) << name;
        EXPECT_TRUE(has_point_with_negative_value(shape, 40)) << name << ": no point with F < 0 in the box";
        const Vec3 centre = 0.5 * (shape.lower + shape.upper);
        const Vec3 half = 0.5 * (shape.upper - shape.lower);
        for (int axis = 0; axis < 3; ++axis) {
            if (shape.clipped[axis]) {
                // The clip is needed: {F ≤ 0} really extends beyond the box along this axis.
                bool found_outside = false;
                for (int sample = 0; sample < 200000 && !found_outside; ++sample) {
                    Vec3 p = random_point(rng, centre - 3.0 * half, centre + 3.0 * half);
                    if (p[axis] >= shape.lower[axis] && p[axis] <= shape.upper[axis]) continue;
                    found_outside = shape.polynomial.value(p) <= 0.0;
                }
                EXPECT_TRUE(found_outside) << name << " is flagged clipped along axis " << axis
                                           << " but no point with F ≤ 0 was found beyond the box";
                continue;
            }
            // F > 0 on both faces orthogonal to the axis …
            for (const double face : {shape.lower[axis], shape.upper[axis]}) {
                for (const Vec3& p : face_samples(shape, axis, face, 200))
                    ASSERT_GT(shape.polynomial.value(p), 0.0) << name << " on the face axis " << axis << " at "
                                                              << p.transpose();
            }
            // … and everywhere beyond them (random points of a box three times as large).
            for (int sample = 0; sample < 20000; ++sample) {
                Vec3 p = random_point(rng, centre - 3.0 * half, centre + 3.0 * half);
                if (p[axis] >= shape.lower[axis] && p[axis] <= shape.upper[axis]) continue;
                ASSERT_GT(shape.polynomial.value(p), 0.0) << name << " beyond axis " << axis << " at " << p.transpose();
            }
        }
    }
}

TEST(NamedShapes, ClippingIsDocumentedByFlags) {
    // Bounded shapes: no clipped axis. Cylinder: clipped along y only. The others are unbounded
    // along every axis (diabolo, and the complements distel, heart, crixxi).
    for (const char* name : {"sphere1", "sphere9", "ellipsoid", "torus", "rcube", "goursat", "goursat-hole", "leopold"})
        EXPECT_EQ(make_shape(name).clipped, (std::array<bool, 3>{false, false, false})) << name;
    EXPECT_EQ(make_shape("cylinder").clipped, (std::array<bool, 3>{false, true, false}));
    for (const char* name : {"distel", "diabolo", "heart", "crixxi"})
        EXPECT_EQ(make_shape(name).clipped, (std::array<bool, 3>{true, true, true})) << name;
}

TEST(NamedShapes, ComplementShapesEncloseTheirCavity) {
    // heart and crixxi as written are {F ≤ 0} = the outside of a bounded solid; the clip box must
    // hold that solid strictly inside, so F < 0 all over the box boundary and F > 0 somewhere in it.
    for (const char* name : {"heart", "crixxi"}) {
        const ImplicitShape shape = make_shape(name);
        for (int axis = 0; axis < 3; ++axis)
            for (const double face : {shape.lower[axis], shape.upper[axis]})
                for (const Vec3& p : face_samples(shape, axis, face, 200))
                    ASSERT_LT(shape.polynomial.value(p), 0.0) << name << " at " << p.transpose();
        EXPECT_GT(shape.polynomial.value(Vec3::Zero()), 0.0) << name << ": the cavity contains the origin";
    }
    EXPECT_GT(make_shape("distel").polynomial.value(Vec3::Zero()), 0.0);
}

TEST(NamedShapes, MakeShapeAcceptsPolynomialStrings) {
    const ImplicitShape shape = make_shape("x^2 + y^2 - 4", 3.0);
    EXPECT_EQ(shape.name, "x^2 + y^2 - 4");
    EXPECT_EQ(shape.lower, Vec3::Constant(-3.0));
    EXPECT_EQ(shape.upper, Vec3::Constant(3.0));
    EXPECT_EQ(shape.clipped, (std::array<bool, 3>{true, true, true}));
    EXPECT_EQ(shape.polynomial.value(Vec3(1.0, 1.0, 5.0)), -2.0);
    EXPECT_EQ(make_shape("x").upper, Vec3::Constant(10.0));

    expect_error_containing([] { make_shape("sphere10"); }, "neither a named shape (sphere1, sphere9", "unknown name");
    expect_error_containing([] { make_shape("sphere10"); }, "unknown variable 's'", "unknown name");
    expect_error_containing([] { make_shape("x", 0.0); }, "default box", "zero box");
    expect_error_containing([] { make_shape("x", std::nan("")); }, "default box", "NaN box");
}

// ---------------------------------------------------------------------------------------------
// Digitization

/// Checks the grid convention and that voxel (i,j,k) is inside iff F(h·(first + (i,j,k))) ≤ 0 and
/// that point is in the box: for every voxel (stride 1), or for every stride-th row plus a random
/// sample of voxels.
void expect_gauss_digitization(const ImplicitShape& shape, double h, std::int64_t stride) {
    const BinaryVolume volume = digitize(shape, h);
    std::int64_t first[3];
    for (int a = 0; a < 3; ++a) {
        first[a] = static_cast<std::int64_t>(std::floor(shape.lower[a] / h)) - 1;
        const std::int64_t last = static_cast<std::int64_t>(std::ceil(shape.upper[a] / h)) + 1;
        ASSERT_EQ(volume.grid.dims[a], last - first[a] + 1) << shape.name << " axis " << a;
        EXPECT_EQ(volume.grid.spacing[a], h);
        EXPECT_EQ(volume.grid.origin[a], h * double(first[a]));
    }
    ASSERT_EQ(volume.mask.size(), static_cast<std::size_t>(volume.grid.voxel_count()));
    auto check = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
        const Vec3 p(h * double(first[0] + i), h * double(first[1] + j), h * double(first[2] + k));
        const bool in_box = (p.array() >= shape.lower.array()).all() && (p.array() <= shape.upper.array()).all();
        const bool expected = in_box && shape.polynomial.value(p) <= 0.0;
        EXPECT_LE((volume.grid.voxel_center(i, j, k) - p).norm(), 1e-12 * (1.0 + p.norm()));
        EXPECT_EQ(volume.inside(i, j, k), expected)
            << shape.name << " h=" << h << " voxel " << i << "," << j << "," << k << " at " << p.transpose();
        return volume.inside(i, j, k) == expected;
    };
    const auto& dims = volume.grid.dims;
    for (std::int64_t k = 0; k < dims[2]; k += stride)
        for (std::int64_t j = 0; j < dims[1]; j += stride)
            for (std::int64_t i = 0; i < dims[0]; ++i)
                if (!check(i, j, k)) return;
    if (stride == 1) return;
    std::mt19937_64 rng(static_cast<std::uint64_t>(dims[0] * 31 + dims[1]));
    for (int sample = 0; sample < 100000; ++sample) {
        const std::int64_t i = std::uniform_int_distribution<std::int64_t>(0, dims[0] - 1)(rng);
        const std::int64_t j = std::uniform_int_distribution<std::int64_t>(0, dims[1] - 1)(rng);
        const std::int64_t k = std::uniform_int_distribution<std::int64_t>(0, dims[2] - 1)(rng);
        if (!check(i, j, k)) return;
    }
}

/// Integer points with x² + y² + z² ≤ r², counted directly.
std::int64_t lattice_points_in_ball(double radius) {
    const int n = static_cast<int>(std::floor(radius));
    std::int64_t count = 0;
    for (int x = -n; x <= n; ++x)
        for (int y = -n; y <= n; ++y)
            for (int z = -n; z <= n; ++z)
                if (x * x + y * y + z * z <= radius * radius) ++count;
    return count;
}

TEST(Digitize, Sphere9VoxelCountIsCloseToTheBallVolume) {
    // The unit cubes centred at the N lattice points of the ball B_R cover B_{R−√3/2} and lie in
    // B_{R+√3/2} (a cube's points are within √3/2 of its centre), so
    //   4/3·π·(R − √3/2)³ ≤ N·h³ ≤ 4/3·π·(R + √3/2)³   with R in units of h.
    // That is a rigorous relative bound of about ±3·(√3/2)·h/R (≈ ±30% at h = 1, ±7.5% at h = 0.25).
    const ImplicitShape sphere = make_shape("sphere9");
    for (const double h : {1.0, 0.5, 0.25}) {
        const BinaryVolume volume = digitize(sphere, h);
        const double count = double(volume.object_voxel_count());
        const double r = 9.0 / h;
        const double half_diagonal = std::sqrt(3.0) / 2.0;
        EXPECT_GE(count, 4.0 / 3.0 * pi * cube(r - half_diagonal)) << "h=" << h;
        EXPECT_LE(count, 4.0 / 3.0 * pi * cube(r + half_diagonal)) << "h=" << h;
        // And exactly the lattice points of the ball, counted directly. (The actual error is far
        // below the bound: N = 3071 against 3053.6 at h = 1, +0.57%; −0.10% at h = 0.5.)
        EXPECT_EQ(volume.object_voxel_count(), lattice_points_in_ball(r)) << "h=" << h;
    }
}

TEST(Digitize, FollowsTheGaussConventionVoxelByVoxel) {
    expect_gauss_digitization(make_shape("sphere9"), 1.0, 1);
    expect_gauss_digitization(make_shape("ellipsoid"), 0.37, 1);  // h does not divide the box
    expect_gauss_digitization(make_shape("torus"), 0.2, 1);
    expect_gauss_digitization(make_shape("goursat"), 0.1, 7);
    expect_gauss_digitization(make_shape("heart"), 0.05, 3);
    expect_gauss_digitization(make_shape("x^3 - y*z + 0.5", 2.0), 0.125, 1);
}

TEST(Digitize, MarginIsBackgroundAndClippedShapesStopAtTheBox) {
    const ImplicitShape cylinder = make_shape("cylinder");
    const double h = 0.5;
    const BinaryVolume volume = digitize(cylinder, h);
    expect_gauss_digitization(cylinder, h, 1);
    const auto& dims = volume.grid.dims;
    std::int64_t on_first_box_slice = 0;
    for (std::int64_t k = 0; k < dims[2]; ++k)
        for (std::int64_t j = 0; j < dims[1]; ++j)
            for (std::int64_t i = 0; i < dims[0]; ++i) {
                const bool margin = i == 0 || j == 0 || k == 0 || i == dims[0] - 1 || j == dims[1] - 1 || k == dims[2] - 1;
                if (margin) {
                    ASSERT_FALSE(volume.inside(i, j, k)) << i << "," << j << "," << k;
                }
                if (j == 1 && volume.inside(i, j, k)) ++on_first_box_slice;
            }
    // y = −10 is the clipping plane: the slice j = 1 (y = −10) is the flat cap of the cylinder.
    EXPECT_DOUBLE_EQ(volume.grid.origin.y() + h, -10.0);
    EXPECT_GT(on_first_box_slice, 0);
}

TEST(Digitize, RejectsBadStepsAndHugeGrids) {
    const ImplicitShape sphere = make_shape("sphere9");
    for (const double h : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()})
        expect_error_containing([&] { digitize(sphere, h); }, "grid step h", "h=" + std::to_string(h));
    expect_error_containing([&] { digitize(sphere, 1e-4); }, "2^34", "huge grid");
    expect_error_containing([&] { digitize(sphere, 1e-300); }, "too large", "absurd grid");
    ImplicitShape broken = sphere;
    broken.lower.x() = 20.0;
    expect_error_containing([&] { digitize(broken, 1.0); }, "invalid box", "inverted box");
}

TEST(Digitize, GoursatAtStepTenthIsFast) {
    const ImplicitShape goursat = make_shape("goursat");
    const auto start = std::chrono::steady_clock::now();
    const BinaryVolume volume = digitize(goursat, 0.1);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("[ timing   ] goursat h=0.1: %lld x %lld x %lld grid, %lld object voxels, %.3f s\n",
                static_cast<long long>(volume.grid.dims[0]), static_cast<long long>(volume.grid.dims[1]),
                static_cast<long long>(volume.grid.dims[2]), static_cast<long long>(volume.object_voxel_count()),
                seconds);
    EXPECT_GT(volume.object_voxel_count(), 0);
    EXPECT_LT(seconds, 10.0);  // typically ~0.1 s; generous for sanitizer and loaded builds
}

// ---------------------------------------------------------------------------------------------
// True normals

TEST(TrueNormal, IsTheUnitGradient) {
    const ImplicitShape sphere = make_shape("sphere9");
    const ImplicitShape torus = make_shape("torus");
    std::mt19937_64 rng(5);
    for (int sample = 0; sample < 100; ++sample) {
        const Vec3 d = random_unit_vector(rng);
        EXPECT_TRUE(true_normal(sphere, 9.0 * d).isApprox(d, 1e-14));
        // Torus point at angles (u, v): its outward normal is (cos v cos u, cos v sin u, sin v).
        std::uniform_real_distribution<double> angle(0.0, 2 * pi);
        const double u = angle(rng), v = angle(rng);
        const Vec3 on_torus((6 + 2 * std::cos(v)) * std::cos(u), (6 + 2 * std::cos(v)) * std::sin(u), 2 * std::sin(v));
        const Vec3 expected(std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v));
        EXPECT_TRUE(true_normal(torus, on_torus).isApprox(expected, 1e-12)) << on_torus.transpose();
    }
    expect_error_containing([&] { true_normal(sphere, Vec3::Zero()); }, "vanishes", "sphere centre");
}

// ---------------------------------------------------------------------------------------------
// Closest point

TEST(ClosestPoint, SpheresAreExact) {
    std::mt19937_64 rng(11);
    struct Case {
        std::string text;
        Vec3 centre;
        double radius;
    };
    const std::vector<Case> cases = {{"sphere9", Vec3::Zero(), 9.0},
                                     {"(x-1)^2+(y+2)^2+(z-0.5)^2-4", Vec3(1.0, -2.0, 0.5), 2.0},
                                     {"2*x^2+2*y^2+2*z^2-8", Vec3::Zero(), 2.0},
                                     {"-x^2-y^2-z^2+2*x+3", Vec3(1.0, 0.0, 0.0), 2.0}};
    for (const Case& c : cases) {
        const ImplicitShape shape = make_shape(c.text);
        for (int sample = 0; sample < 200; ++sample) {
            const Vec3 p = random_point(rng, c.centre - Vec3::Constant(3 * c.radius), c.centre + Vec3::Constant(3 * c.radius));
            const Vec3 xi = closest_point(shape, p);
            const Vec3 expected = c.centre + c.radius * (p - c.centre).normalized();
            EXPECT_LE((xi - expected).norm(), 1e-13 * (1 + c.radius)) << c.text << " from " << p.transpose();
            EXPECT_NEAR((p - xi).norm(), std::abs((p - c.centre).norm() - c.radius), 1e-13 * (1 + c.radius));
        }
        const Vec3 from_centre = closest_point(shape, c.centre);
        EXPECT_NEAR((from_centre - c.centre).norm(), c.radius, 1e-13) << c.text;
    }
    expect_error_containing([] { closest_point(make_shape("x^2+y^2+z^2+1"), Vec3::Zero()); }, "empty", "imaginary");
    expect_error_containing([] { closest_point(make_shape("3"), Vec3::Zero()); }, "constant", "constant F");
}

TEST(ClosestPoint, TiltedPlaneIsExact) {
    const Vec3 normal(1.0, 2.0, 3.0);
    const double offset = 0.7;
    const ImplicitShape plane = make_plane_shape(normal, offset, 5.0);
    const Vec3 n = normal.normalized();
    EXPECT_EQ(plane.clipped, (std::array<bool, 3>{true, true, true}));
    EXPECT_EQ(plane.upper, Vec3::Constant(5.0));
    std::mt19937_64 rng(3);
    for (int sample = 0; sample < 200; ++sample) {
        const Vec3 p = random_point(rng, plane.lower, plane.upper);
        EXPECT_NEAR(plane.polynomial.value(p), n.dot(p) - offset, 1e-14);
        const Vec3 xi = closest_point(plane, p);
        EXPECT_LE((xi - (p - (n.dot(p) - offset) * n)).norm(), 1e-14);
        EXPECT_TRUE(true_normal(plane, p).isApprox(n, 1e-15));
    }
    expect_gauss_digitization(plane, 0.1, 3);
    EXPECT_THROW(make_plane_shape(Vec3::Zero(), 0.0, 1.0), Error);
    EXPECT_THROW(make_plane_shape(normal, std::nan(""), 1.0), Error);
    EXPECT_THROW(make_plane_shape(normal, 0.0, -1.0), Error);
}

/// A shape with independently computed surface samples, to check that ξ is the closest.
struct SampledSurface {
    std::string name;
    std::vector<Vec3> samples;
    double reach;  ///< points closer than this to the surface have a unique closest point
};

SampledSurface torus_samples() {
    SampledSurface s{"torus", {}, 2.0};
    const int n = 400;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n / 2; ++b) {
            const double u = 2 * pi * a / n, v = 2 * pi * b / (n / 2);
            s.samples.emplace_back((6 + 2 * std::cos(v)) * std::cos(u), (6 + 2 * std::cos(v)) * std::sin(u),
                                   2 * std::sin(v));
        }
    return s;
}

SampledSurface ellipsoid_samples() {
    // Smallest radius of curvature of the ellipsoid: b²/a with a = √90 the largest and b = √30
    // the smallest semi-axis (≈ 3.16).
    SampledSurface s{"ellipsoid", {}, 30.0 / std::sqrt(90.0)};
    const int n = 300;
    for (int a = 0; a <= n; ++a)
        for (int b = 0; b < 2 * n; ++b) {
            const double theta = pi * a / n, phi = pi * b / n;
            s.samples.emplace_back(std::sqrt(30.0) * std::sin(theta) * std::cos(phi),
                                   std::sqrt(45.0) * std::sin(theta) * std::sin(phi), std::sqrt(90.0) * std::cos(theta));
        }
    return s;
}

SampledSurface goursat_samples() {
    // Along the ray t·d (|d| = 1), F = 0.03·S4·t⁴ − 2·t² − 8 with S4 = Σ d_i⁴: a quadratic in t²
    // with a single positive root, so the shape is star-shaped and each ray meets F = 0 once.
    SampledSurface s{"goursat", {}, 0.3};
    std::mt19937_64 rng(17);
    for (int sample = 0; sample < 120000; ++sample) {
        const Vec3 d = random_unit_vector(rng);
        const double s4 = std::pow(d.x(), 4) + std::pow(d.y(), 4) + std::pow(d.z(), 4);
        const double t2 = (2.0 + std::sqrt(4.0 + 4.0 * 0.03 * s4 * 8.0)) / (2.0 * 0.03 * s4);
        s.samples.push_back(std::sqrt(t2) * d);
    }
    return s;
}

TEST(ClosestPoint, PolynomialShapesGiveTheClosestSurfacePoint) {
    const std::vector<SampledSurface> surfaces = {torus_samples(), ellipsoid_samples(), goursat_samples()};
    for (const SampledSurface& surface : surfaces) {
        const ImplicitShape shape = make_shape(surface.name);
        for (const Vec3& s : surface.samples)
            ASSERT_LT(std::abs(shape.polynomial.value(s)), 1e-9 * shape.polynomial.gradient(s).norm()) << surface.name;
        std::mt19937_64 rng(23);
        std::uniform_int_distribution<std::size_t> pick(0, surface.samples.size() - 1);
        std::uniform_real_distribution<double> offset(-0.9 * surface.reach, 0.9 * surface.reach);
        for (int trial = 0; trial < 60; ++trial) {
            const Vec3 p = surface.samples[pick(rng)] + offset(rng) * random_unit_vector(rng);
            const Vec3 xi = closest_point(shape, p);
            const Vec3 g = shape.polynomial.gradient(xi);
            // On the surface, to rounding: |F(ξ)|/|∇F(ξ)| estimates the distance to F = 0.
            EXPECT_LT(std::abs(shape.polynomial.value(xi)) / g.norm(), 1e-12) << surface.name << " from " << p.transpose();
            // p − ξ along the normal.
            EXPECT_LT((p - xi).cross(g.normalized()).norm(), 1e-10) << surface.name << " from " << p.transpose();
            // At least as close as every sampled surface point.
            double nearest_sample = std::numeric_limits<double>::infinity();
            for (const Vec3& s : surface.samples) nearest_sample = std::min(nearest_sample, (p - s).norm());
            EXPECT_LE((p - xi).norm(), nearest_sample + 1e-12) << surface.name << " from " << p.transpose();
            if (surface.name == "torus") {
                // Exact: the closest point of the tube circle, pushed out by the minor radius 2.
                const Vec3 ring_point = 6.0 * Vec3(p.x(), p.y(), 0.0).normalized();
                const Vec3 expected = ring_point + 2.0 * (p - ring_point).normalized();
                EXPECT_LE((xi - expected).norm(), 1e-12) << "torus from " << p.transpose();
            }
        }
        // Surface points project onto themselves.
        for (int trial = 0; trial < 20; ++trial) {
            const Vec3 s = surface.samples[pick(rng)];
            EXPECT_LE((closest_point(shape, s) - s).norm(), 1e-12) << surface.name;
        }
    }
}

TEST(ClosestPoint, FindsTheSurfaceFromACriticalPointOfF) {
    // Inside goursat, F has a local maximum F = −8 at the origin: Newton on F climbs towards it
    // and stalls below zero. Along the ray t·d, F = 0.03·S4·t⁴ − 2t² − 8 (S4 = Σd_i⁴), so the
    // surface is nearest along the axes (S4 = 1), at t² = (2 + √(4 + 0.96))/0.06.
    const ImplicitShape goursat = make_shape("goursat");
    const double axis_distance = std::sqrt((2.0 + std::sqrt(4.0 + 0.96)) / 0.06);
    for (const Vec3& p : {Vec3(0.0, 0.0, 0.0), Vec3(1e-3, -2e-3, 5e-4), Vec3(0.05, 0.02, -0.03)}) {
        const Vec3 xi = closest_point(goursat, p);
        EXPECT_LT(std::abs(goursat.polynomial.value(xi)) / goursat.polynomial.gradient(xi).norm(), 1e-12);
        EXPECT_NEAR(xi.cwiseAbs().maxCoeff(), axis_distance, 0.1) << "ξ = " << xi.transpose();
        EXPECT_LE((p - xi).norm(), axis_distance + p.norm() + 1e-12) << "ξ = " << xi.transpose();
        if (p.norm() == 0.0) {
            EXPECT_NEAR(xi.norm(), axis_distance, 1e-12);
            EXPECT_NEAR(xi.cwiseAbs().maxCoeff(), xi.norm(), 1e-9) << "on an axis: " << xi.transpose();
        }
    }
}

/// A point of F = 0 found by bisection between random points of the box where F has opposite
/// signs (independent of closest_point()).
bool random_surface_point(const ImplicitShape& shape, std::mt19937_64& rng, Vec3& surface_point) {
    const Polynomial& f = shape.polynomial;
    Vec3 a = random_point(rng, shape.lower, shape.upper);
    Vec3 b = random_point(rng, shape.lower, shape.upper);
    double fa = f.value(a);
    if (!((fa < 0.0 && f.value(b) > 0.0) || (fa > 0.0 && f.value(b) < 0.0))) return false;
    for (int iteration = 0; iteration < 200; ++iteration) {
        const Vec3 middle = 0.5 * (a + b);
        const double fm = f.value(middle);
        if ((fm < 0.0) == (fa < 0.0)) {
            a = middle;
            fa = fm;
        } else {
            b = middle;
        }
    }
    surface_point = a;
    return true;
}

TEST(ClosestPoint, OtherNamedShapesGiveLocallyClosestPoints) {
    std::mt19937_64 rng(31);
    for (const char* name : {"goursat-hole", "leopold", "rcube", "cylinder", "distel", "diabolo", "heart", "crixxi"}) {
        const ImplicitShape shape = make_shape(name);
        const Polynomial& f = shape.polynomial;
        const double scale = std::max(1.0, shape.upper.norm());
        const double max_offset = 0.05 * (shape.upper - shape.lower).minCoeff();
        std::uniform_real_distribution<double> offset(0.0, max_offset);
        int checked = 0;
        for (int attempt = 0; attempt < 100000 && checked < 100; ++attempt) {
            Vec3 s;
            if (!random_surface_point(shape, rng, s)) continue;
            ++checked;
            const Vec3 p = s + offset(rng) * random_unit_vector(rng);
            const Vec3 xi = closest_point(shape, p);
            const Vec3 g = f.gradient(xi);
            // On the surface to rounding (in value, which also holds at singular points) …
            EXPECT_LE(std::abs(f.value(xi)), 1e-12 * term_magnitude(f, xi)) << name << " from " << p.transpose();
            // … at least as close as the surface point p was made from …
            EXPECT_LE((p - xi).norm(), (p - s).norm() + 1e-12 * scale) << name << " from " << p.transpose();
            // … and, at regular points, with p − ξ along the normal.
            if (g.norm() > 1e-3 * f.gradient(s).norm() && g.norm() > 1e-6) {
                EXPECT_LT((p - xi).cross(g.normalized()).norm(), 1e-10 * scale) << name << " from " << p.transpose();
            }
        }
        EXPECT_EQ(checked, 100) << name;
    }
}

TEST(ClosestPoint, HeartCuspIsALocalMinimum) {
    // The classical heart has a singular point (∇F = 0) at its bottom tip (0, 0, −1), where F
    // vanishes to third order along the axis: there double precision fixes F = 0 only to about
    // (1e-16)^(1/3) ≈ 1e-5. From points below the tip, the closest surface point is the tip.
    const Vec3 tip(0.0, 0.0, -1.0);
    const ImplicitShape heart = make_shape("heart");
    EXPECT_EQ(heart.polynomial.value(tip), 0.0);
    EXPECT_EQ(heart.polynomial.gradient(tip).norm(), 0.0);
    for (const Vec3& p : {Vec3(0.0, 0.0, -1.05), Vec3(0.003, -0.002, -1.2), Vec3(0.01, 0.0, -1.1)}) {
        const Vec3 xi = closest_point(heart, p);
        EXPECT_LE((p - xi).norm(), (p - tip).norm() + 1e-5) << p.transpose();
        EXPECT_LE((xi - tip).norm(), 1e-3) << p.transpose() << " -> " << xi.transpose();
        EXPECT_LE(std::abs(heart.polynomial.value(xi)), 1e-12);
    }
    // The tip is a local minimum of the distance even for some points beside it (the surface
    // leaves the tip vertically, like |x|^(2/3)), so from there a local search may stop at the
    // tip or reach a sheet; either way the result is on the surface and no farther than the tip.
    const Vec3 p(-0.0080071159187562468, -0.028763070777432898, -1.0043940840860235);
    const Vec3 xi = closest_point(heart, p);
    EXPECT_LE(std::abs(heart.polynomial.value(xi)), 1e-12);
    EXPECT_LE((p - xi).norm(), (p - tip).norm() + 1e-5);
}

}  // namespace
}  // namespace dsreg
