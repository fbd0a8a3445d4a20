// dsreg — internal: the evaluation kernel shared by Polynomial::value() and digitize().
//
// A monomial c·x^a·y^b·z^c is evaluated as ((c·z^c)·y^b)·x^a with powers read from tables
// filled by repeated multiplication, and the monomials are summed in their canonical order.
// Polynomial::value() and digitize() both run that sum through the one compiled function
// evaluate_row() (value() on a row of length 1), so they agree bit for bit whatever the
// compiler does with floating-point contraction (FMA).
#pragma once

#include <cstddef>

#include "dsreg/implicit_shape.hpp"

namespace dsreg::detail {

/// Size of a power table: exponents 0 … Polynomial::max_degree.
constexpr int power_table_size = Polynomial::max_degree + 1;

/// table[k] = v^k for k = 0 … max_power.
inline void fill_powers(double v, int max_power, double* table) {
    table[0] = 1.0;
    for (int k = 1; k <= max_power; ++k) table[k] = table[k - 1] * v;
}

/// The part of a monomial that does not depend on x: (c·z^ez)·y^ey.
inline double row_weight(const Polynomial::Monomial& m, const double* y_powers, const double* z_powers) {
    return (m.coefficient * z_powers[m.ez]) * y_powers[m.ey];
}

/// sums[i] = F(x_i, y, z) for a row of points sharing y and z, where
/// x_powers[e·row_length + i] = x_i^e (e = 0 … f.max_exponent(0)) and y_powers, z_powers are
/// power tables of y and z.
void evaluate_row(const Polynomial& f, const double* y_powers, const double* z_powers, const double* x_powers,
                  std::size_t row_length, double* sums);

}  // namespace dsreg::detail
