// dsreg — volume of an implicit solid {F ≤ 0} ∩ box: exact chord lengths along x lines,
// nested adaptive Simpson quadrature over y and z.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"

namespace dsreg {
namespace {

constexpr int max_terms = Polynomial::max_degree + 1;

/// F restricted to an x line and all its derivatives: level k holds the k-th derivative,
/// coefficients c[0] + c[1]·x + … of degree `degree - k`. Fixed storage: no allocation per line.
class LinePolynomial {
public:
    /// F(x, y, z) as a polynomial in x.
    LinePolynomial(const Polynomial& f, double y, double z) {
        std::fill(coefficients_[0].begin(), coefficients_[0].begin() + f.max_exponent(0) + 1, 0.0);
        for (const Polynomial::Monomial& m : f.monomials()) {
            double term = m.coefficient;
            for (int k = 0; k < m.ey; ++k) term *= y;
            for (int k = 0; k < m.ez; ++k) term *= z;
            coefficients_[0][std::size_t(m.ex)] += term;
        }
        degree_ = f.max_exponent(0);
        while (degree_ > 0 && coefficients_[0][std::size_t(degree_)] == 0.0) --degree_;
        for (int k = 1; k <= degree_; ++k)
            for (int e = 0; e <= degree_ - k; ++e)
                coefficients_[std::size_t(k)][std::size_t(e)] = double(e + 1) * coefficients_[std::size_t(k - 1)][std::size_t(e + 1)];
    }

    int degree() const { return degree_; }

    /// Value of the k-th derivative at x (Horner).
    double value(int k, double x) const {
        const auto& c = coefficients_[std::size_t(k)];
        double v = 0;
        for (int e = degree_ - k; e >= 0; --e) v = v * x + c[std::size_t(e)];
        return v;
    }

private:
    int degree_ = 0;
    std::array<std::array<double, max_terms>, max_terms> coefficients_;
};

/// The root in [lo, hi] of the k-th derivative of p, monotone there with values of opposite
/// signs at the ends: Newton steps kept inside the bracket, bisection otherwise.
double bracketed_root(const LinePolynomial& p, int k, double lo, double hi) {
    const bool increasing = p.value(k, lo) < 0;
    double x = 0.5 * (lo + hi);
    for (int iteration = 0; iteration < 100; ++iteration) {
        const double value = p.value(k, x);
        if (value == 0.0) return x;
        if ((value < 0) == increasing) lo = x;
        else hi = x;
        if (hi - lo <= 4 * std::numeric_limits<double>::epsilon() * std::max(std::abs(lo), std::abs(hi))) break;
        const double slope = p.value(k + 1, x);
        const double newton = slope != 0.0 ? x - value / slope : lo;
        x = (newton > lo && newton < hi) ? newton : 0.5 * (lo + hi);
    }
    return 0.5 * (lo + hi);
}

/// Length of {x ∈ [a, b] : F ≤ 0}. [a, b] is split into pieces on which F is monotone, from the
/// top derivative down: the pieces of derivative k−1 are cut at the sign changes of derivative k
/// on its own pieces. Then each piece of F contributes all, none, or the part up to its root.
double inside_length(const LinePolynomial& p, double a, double b) {
    if (p.degree() == 0) return p.value(0, a) <= 0 ? b - a : 0.0;
    double length = 0;
    std::array<double, max_terms + 1> breaks{a, b}, next{};
    int count = 2;
    for (int k = p.degree() - 1; k >= 1; --k) {  // pieces of derivative k−1 from the roots of derivative k
        int next_count = 0;
        next[std::size_t(next_count++)] = a;
        for (int i = 0; i + 1 < count; ++i) {
            const double lo = breaks[std::size_t(i)], hi = breaks[std::size_t(i + 1)];
            const double v_lo = p.value(k, lo), v_hi = p.value(k, hi);
            if ((v_lo < 0 && v_hi > 0) || (v_lo > 0 && v_hi < 0)) next[std::size_t(next_count++)] = bracketed_root(p, k, lo, hi);
        }
        next[std::size_t(next_count++)] = b;
        breaks = next;
        count = next_count;
    }
    for (int i = 0; i + 1 < count; ++i) {
        const double lo = breaks[std::size_t(i)], hi = breaks[std::size_t(i + 1)];
        const bool lo_inside = p.value(0, lo) <= 0, hi_inside = p.value(0, hi) <= 0;
        if (lo_inside && hi_inside) {
            length += hi - lo;
        } else if (lo_inside != hi_inside) {
            const double root = bracketed_root(p, 0, lo, hi);
            length += lo_inside ? root - lo : hi - root;
        }
    }
    return length;
}

/// Chord length of the solid along the x line through (y, z), within the box.
double chord_length(const ImplicitShape& shape, double y, double z) {
    return inside_length(LinePolynomial(shape.polynomial, y, z), shape.lower.x(), shape.upper.x());
}

/// One piece [lo, hi] of a globally adaptive Simpson quadrature, with f at its ends, quarter
/// points and midpoint.
struct SimpsonPiece {
    double lo, hi;
    std::array<double, 5> f;  ///< at lo, lo + w/4, lo + w/2, lo + 3w/4, hi
    double estimate = 0;      ///< composite Simpson on the two halves, plus Richardson correction
    double error = 0;         ///< |two halves − one panel|: conservative (no /15) near √ singularities

    void finish() {
        const double w = hi - lo;
        const double one_panel = w / 6.0 * (f[0] + 4.0 * f[2] + f[4]);
        const double two_panels = w / 12.0 * (f[0] + 4.0 * f[1] + 2.0 * f[2] + 4.0 * f[3] + f[4]);
        error = std::abs(two_panels - one_panel);
        estimate = two_panels + (two_panels - one_panel) / 15.0;
    }
    bool operator<(const SimpsonPiece& other) const { return error < other.error; }  // max-heap on error
};

/// ∫_a^b f by globally adaptive Simpson quadrature (as in QUADPACK): [a, b] is first cut into
/// `intervals` equal pieces (features wider than a piece are surely seen), then the piece with
/// the largest error estimate is halved until the summed estimate is below `tolerance` or
/// `max_evaluations` values of f have been used. This converges at the kinks and √-type
/// singularities that chord lengths have at silhouettes, whose places are not known in advance,
/// and its cost stays bounded where the integrand is only known to rounding noise (chords
/// through near-multiple roots of F, e.g. at cusps).
template <class Function>
double adaptive_simpson(const Function& f, double a, double b, double tolerance, int intervals, int max_evaluations) {
    std::vector<SimpsonPiece> heap;
    heap.reserve(std::size_t(intervals) + std::size_t(max_evaluations) / 2 + 1);
    const double width = (b - a) / intervals;
    double previous_end_value = f(a);
    int evaluations = 1;
    for (int i = 0; i < intervals; ++i) {
        SimpsonPiece piece;
        piece.lo = a + i * width;
        piece.hi = i + 1 == intervals ? b : piece.lo + width;
        const double w = piece.hi - piece.lo;
        piece.f = {previous_end_value, f(piece.lo + 0.25 * w), f(piece.lo + 0.5 * w), f(piece.lo + 0.75 * w), f(piece.hi)};
        evaluations += 4;
        previous_end_value = piece.f[4];
        piece.finish();
        heap.push_back(piece);
    }
    std::make_heap(heap.begin(), heap.end());
    double total_error = 0;
    for (const SimpsonPiece& piece : heap) total_error += piece.error;
    while (total_error > tolerance && evaluations + 4 <= max_evaluations) {
        std::pop_heap(heap.begin(), heap.end());
        const SimpsonPiece worst = heap.back();
        heap.pop_back();
        total_error -= worst.error;
        const double mid = 0.5 * (worst.lo + worst.hi), quarter = 0.25 * (worst.hi - worst.lo);
        SimpsonPiece left{worst.lo, mid, {worst.f[0], f(worst.lo + 0.5 * quarter), worst.f[1], f(worst.lo + 1.5 * quarter), worst.f[2]}};
        SimpsonPiece right{mid, worst.hi, {worst.f[2], f(mid + 0.5 * quarter), worst.f[3], f(mid + 1.5 * quarter), worst.f[4]}};
        evaluations += 4;
        for (SimpsonPiece* piece : {&left, &right}) {
            piece->finish();
            total_error += piece->error;
            heap.push_back(*piece);
            std::push_heap(heap.begin(), heap.end());
        }
    }
    double sum = 0;
    for (const SimpsonPiece& piece : heap) sum += piece.estimate;
    return sum;
}

/// Error asked of the quadrature, relative to the box volume.
constexpr double relative_tolerance = 1e-6;
/// Budgets of evaluations: per cross-section area (chord lengths) and per z cell (areas).
constexpr int max_chords_per_area = 4000;
constexpr int max_areas_per_cell = 400;

}  // namespace

double shape_volume(const ImplicitShape& shape, int cells_per_axis) {
    if (cells_per_axis < 8) throw Error("shape_volume: cells_per_axis must be at least 8");
    const Eigen::Vector3d size = shape.upper - shape.lower;
    if (!size.allFinite() || (size.array() < 0).any()) throw Error("shape_volume: shape '" + shape.name + "' has an invalid box");
    if ((size.array() == 0).any()) return 0.0;
    const double tolerance = relative_tolerance * size.prod();
    // Inner integral: the area of the cross-section at height z, ∫ chord dy, to a tenth of the
    // volume tolerance spread over the z extent.
    const double area_tolerance = 0.1 * tolerance / size.z();
    auto cross_section_area = [&](double z) {
        return adaptive_simpson([&](double y) { return chord_length(shape, y, z); }, shape.lower.y(), shape.upper.y(),
                                area_tolerance, cells_per_axis, max_chords_per_area);
    };
    // Outer integral over z, cut into cells_per_axis cells integrated in parallel.
    const double dz = size.z() / cells_per_axis;
    // The cells' integrals added in cell order (a reduction would add them in the order the
    // threads finish: other bits from run to run).
    std::vector<double> cell_volume(static_cast<std::size_t>(cells_per_axis), 0.0);
#pragma omp parallel for schedule(dynamic, 1)
    for (int k = 0; k < cells_per_axis; ++k) {
        const double z0 = shape.lower.z() + k * dz, z1 = k + 1 == cells_per_axis ? shape.upper.z() : z0 + dz;
        cell_volume[std::size_t(k)] = adaptive_simpson(cross_section_area, z0, z1, tolerance / cells_per_axis, 1, max_areas_per_cell);
    }
    double volume = 0;
    for (const double v : cell_volume) volume += v;
    return volume;
}

}  // namespace dsreg
