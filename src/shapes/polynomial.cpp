// dsreg — Polynomial: parser (recursive descent straight to the expanded form) and evaluation.
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "dsreg/error.hpp"
#include "dsreg/implicit_shape.hpp"
#include "polynomial_eval.hpp"

namespace dsreg {
namespace {

using Monomial = Polynomial::Monomial;
/// An expanded polynomial in canonical order (see Polynomial::monomials()).
using Terms = std::vector<Monomial>;

int total_degree(const Monomial& m) { return m.ex + m.ey + m.ez; }

/// Canonical order: decreasing total degree, then decreasing (ex, ey, ez).
bool canonical_less(const Monomial& a, const Monomial& b) {
    const int da = total_degree(a);
    const int db = total_degree(b);
    if (da != db) return da > db;
    if (a.ex != b.ex) return a.ex > b.ex;
    if (a.ey != b.ey) return a.ey > b.ey;
    return a.ez > b.ez;
}

bool same_exponents(const Monomial& a, const Monomial& b) {
    return a.ex == b.ex && a.ey == b.ey && a.ez == b.ez;
}

/// Sorts, combines like terms (in the order they were written) and drops zero coefficients.
Terms canonicalize(Terms terms) {
    std::stable_sort(terms.begin(), terms.end(), canonical_less);
    Terms result;
    result.reserve(terms.size());
    for (const Monomial& m : terms) {
        if (!result.empty() && same_exponents(result.back(), m)) {
            result.back().coefficient += m.coefficient;
        } else {
            result.push_back(m);
        }
    }
    result.erase(std::remove_if(result.begin(), result.end(),
                                [](const Monomial& m) { return m.coefficient == 0.0; }),
                 result.end());
    return result;
}

/// Degree of a canonical term list (0 for the zero polynomial).
int degree_of(const Terms& terms) { return terms.empty() ? 0 : total_degree(terms.front()); }

int max_exponent_of(const Terms& terms, int axis) {
    int result = 0;
    for (const Monomial& m : terms) result = std::max(result, axis == 0 ? m.ex : axis == 1 ? m.ey : m.ez);
    return result;
}

Terms constant_terms(double value) {
    if (value == 0.0) return {};
    return {Monomial{value, 0, 0, 0}};
}

Terms variable_terms(int axis) {
    return {Monomial{1.0, axis == 0 ? 1 : 0, axis == 1 ? 1 : 0, axis == 2 ? 1 : 0}};
}

/// Multiplies every coefficient by a non-zero factor (order and non-zeros are kept).
Terms scaled(Terms terms, double factor) {
    for (Monomial& m : terms) m.coefficient *= factor;
    return terms;
}

bool is_constant(const Terms& terms) { return terms.size() == 1 && total_degree(terms.front()) == 0; }

/// Size of the dense (ex, ey, ez) array a·b would be accumulated in.
double dense_product_size(const Terms& a, const Terms& b) {
    double size = 1.0;
    for (int axis = 0; axis < 3; ++axis) size *= max_exponent_of(a, axis) + max_exponent_of(b, axis) + 1;
    return size;
}

/// Pairs of terms against the cells of the dense array: few pairs (a monomial times anything,
/// short factors of high degree) are summed by sorting them, many by the dense array.
bool product_is_sparse(const Terms& a, const Terms& b) {
    return double(a.size()) * double(b.size()) < dense_product_size(a, b);
}

/// Work of product_of(a, b): one multiply-add per pair, plus the dense array or the sort.
double product_work(const Terms& a, const Terms& b) {
    const double pairs = double(a.size()) * double(b.size());
    return pairs + (product_is_sparse(a, b) ? pairs * std::log2(pairs + 2.0) : dense_product_size(a, b));
}

/// Product of two expanded polynomials. Each coefficient sums its pairs' products in the order
/// (term of a, term of b) either way, so both ways give the same bits. The caller guarantees
/// degree(a) + degree(b) ≤ max_degree, so the dense array has at most 65³ entries.
Terms product_of(const Terms& a, const Terms& b) {
    if (a.empty() || b.empty()) return {};
    if (is_constant(a) || is_constant(b)) {  // scaling keeps the order; drop underflows to 0
        Terms result = is_constant(a) ? scaled(b, a.front().coefficient) : scaled(a, b.front().coefficient);
        result.erase(std::remove_if(result.begin(), result.end(), [](const Monomial& m) { return m.coefficient == 0.0; }),
                     result.end());
        return result;
    }
    if (product_is_sparse(a, b)) {
        Terms pairs;
        pairs.reserve(a.size() * b.size());
        for (const Monomial& ma : a)
            for (const Monomial& mb : b)
                pairs.push_back(Monomial{ma.coefficient * mb.coefficient, ma.ex + mb.ex, ma.ey + mb.ey, ma.ez + mb.ez});
        return canonicalize(std::move(pairs));
    }
    const int nx = max_exponent_of(a, 0) + max_exponent_of(b, 0) + 1;
    const int ny = max_exponent_of(a, 1) + max_exponent_of(b, 1) + 1;
    const int nz = max_exponent_of(a, 2) + max_exponent_of(b, 2) + 1;
    std::vector<double> dense(static_cast<std::size_t>(nx) * ny * nz, 0.0);
    auto cell = [&](int ex, int ey, int ez) { return (static_cast<std::size_t>(ez) * ny + ey) * nx + ex; };
    for (const Monomial& ma : a) {
        for (const Monomial& mb : b) {
            dense[cell(ma.ex + mb.ex, ma.ey + mb.ey, ma.ez + mb.ez)] += ma.coefficient * mb.coefficient;
        }
    }
    Terms result;
    for (int ez = 0; ez < nz; ++ez)
        for (int ey = 0; ey < ny; ++ey)
            for (int ex = 0; ex < nx; ++ex) {
                const double c = dense[cell(ex, ey, ez)];
                if (c != 0.0) result.push_back(Monomial{c, ex, ey, ez});
            }
    return canonicalize(std::move(result));
}

/// The polynomial text as quoted in error messages (long texts shortened).
std::string echo(const std::string& text) {
    constexpr std::size_t max_echo = 80;
    return text.size() <= max_echo ? text : text.substr(0, max_echo - 3) + "...";
}

bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_letter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }

/// Recursive-descent parser producing expanded terms directly (grammar in implicit_shape.hpp).
class Parser {
public:
    explicit Parser(const std::string& text) : text_(text) {}

    Terms parse_all() {
        skip_spaces();
        if (at_end()) fail_here("empty expression");
        Terms result = parse_sum();
        skip_spaces();
        if (!at_end()) complain_about_leftover();
        return result;
    }

private:
    static constexpr int max_nesting = 256;  // parentheses and unary signs; bounds the recursion
    static constexpr double max_work = 1e8;  // multiply-adds and terms handled while expanding

    /// Counts nesting depth for the lifetime of one recursive call.
    class NestingGuard {
    public:
        explicit NestingGuard(Parser& parser) : parser_(parser) {
            if (++parser_.depth_ > max_nesting)
                parser_.fail_here("nesting deeper than " + std::to_string(max_nesting) + " levels");
        }
        ~NestingGuard() { --parser_.depth_; }
        NestingGuard(const NestingGuard&) = delete;
        NestingGuard& operator=(const NestingGuard&) = delete;

    private:
        Parser& parser_;
    };

    /// The terms of all summands are collected and combined once at the end, so a long sum
    /// costs O(n log n), not O(n²).
    Terms parse_sum() {
        Terms all = parse_product();
        for (;;) {
            skip_spaces();
            if (at_end() || (peek() != '+' && peek() != '-')) return canonicalize(std::move(all));
            const double sign = peek() == '+' ? 1.0 : -1.0;
            const std::size_t operator_pos = pos_++;
            const Terms summand = scaled(parse_product(), sign);
            charge(double(summand.size()), operator_pos);
            all.insert(all.end(), summand.begin(), summand.end());
        }
    }

    Terms parse_product() {
        Terms result = parse_signed();
        for (;;) {
            skip_spaces();
            if (at_end() || peek() != '*') return result;
            const std::size_t operator_pos = pos_++;
            skip_spaces();
            if (!at_end() && peek() == '*') fail_here("unexpected '*' (write x^2 for powers, not x**2)");
            const Terms factor = parse_signed();
            check_degree(degree_of(result) + degree_of(factor), operator_pos);
            result = multiply(result, factor, operator_pos);
        }
    }

    Terms parse_signed() {
        skip_spaces();
        if (!at_end() && (peek() == '+' || peek() == '-')) {
            NestingGuard guard(*this);
            const double sign = peek() == '+' ? 1.0 : -1.0;
            ++pos_;
            return scaled(parse_signed(), sign);
        }
        return parse_power();
    }

    Terms parse_power() {
        Terms base = parse_primary();
        skip_spaces();
        if (at_end() || peek() != '^') return base;
        const std::size_t operator_pos = pos_++;
        const int exponent = parse_exponent();
        check_degree(degree_of(base) * exponent, operator_pos);
        skip_spaces();
        if (!at_end() && peek() == '^') fail_here("chained '^' is ambiguous; use parentheses, e.g. (x^2)^3");
        return raise(base, exponent, operator_pos);
    }

    Terms parse_primary() {
        skip_spaces();
        if (at_end()) fail_here("expected a number, a variable (x, y, z) or '(' but the text ends");
        const char c = peek();
        if (c == '(') {
            NestingGuard guard(*this);
            const std::size_t open_pos = pos_++;
            skip_spaces();
            if (!at_end() && peek() == ')') fail_here("empty parentheses");
            Terms inner = parse_sum();
            skip_spaces();
            if (at_end()) fail_at("unclosed '('", open_pos);
            if (peek() != ')') complain_about_leftover();
            ++pos_;
            return inner;
        }
        if (c == 'x' || c == 'y' || c == 'z') {
            ++pos_;
            return variable_terms(c - 'x');
        }
        if (is_digit(c) || c == '.') return constant_terms(parse_number());
        if (is_letter(c)) fail_here("unknown variable '" + std::string(1, c) + "' (the variables are x, y, z)");
        fail_here("unexpected " + describe(pos_));
    }

    /// A decimal number: digits [. digits] [e|E [+|-] digits], at least one mantissa digit.
    double parse_number() {
        const std::size_t start = pos_;
        std::size_t mantissa_digits = 0;
        while (!at_end() && is_digit(peek())) ++pos_, ++mantissa_digits;
        if (!at_end() && peek() == '.') {
            ++pos_;
            while (!at_end() && is_digit(peek())) ++pos_, ++mantissa_digits;
        }
        if (mantissa_digits == 0) fail_at("a number needs at least one digit", start);
        if (!at_end() && (peek() == 'e' || peek() == 'E')) {
            ++pos_;
            if (!at_end() && (peek() == '+' || peek() == '-')) ++pos_;
            if (at_end() || !is_digit(peek()))
                fail_at("malformed number '" + text_.substr(start, pos_ - start) + "' (exponent digits missing)", start);
            while (!at_end() && is_digit(peek())) ++pos_;
        }
        double value = 0.0;
        const char* first = text_.data() + start;
        const char* last = text_.data() + pos_;
        const auto [end, error] = std::from_chars(first, last, value);
        if (error == std::errc::result_out_of_range || (error == std::errc() && !std::isfinite(value)))
            fail_at("number '" + text_.substr(start, pos_ - start) + "' is out of range", start);
        if (error != std::errc() || end != last)
            fail_at("malformed number '" + text_.substr(start, pos_ - start) + "'", start);
        return value;
    }

    /// The integer after '^': digits only, at most max_degree.
    int parse_exponent() {
        skip_spaces();
        const std::size_t start = pos_;
        if (at_end()) fail_here("expected a non-negative integer exponent after '^' but the text ends");
        if (!is_digit(peek())) {
            if (peek() == '-' || peek() == '+' || peek() == '.' || peek() == '(' || is_letter(peek()))
                fail_here("the exponent must be a non-negative integer literal");
            fail_here("expected a non-negative integer exponent after '^', found " + describe(pos_));
        }
        long long exponent = 0;
        while (!at_end() && is_digit(peek())) {
            if (exponent <= Polynomial::max_degree) exponent = exponent * 10 + (peek() - '0');
            ++pos_;
        }
        if (!at_end() && (peek() == '.' || peek() == 'e' || peek() == 'E'))
            fail_at("the exponent must be a non-negative integer literal", start);
        if (exponent > Polynomial::max_degree)
            fail_at("exponent " + text_.substr(start, pos_ - start) + " exceeds the maximum " +
                        std::to_string(Polynomial::max_degree),
                    start);
        return static_cast<int>(exponent);
    }

    /// a·b, counted against the work budget.
    Terms multiply(const Terms& a, const Terms& b, std::size_t operator_pos) {
        const bool by_constant = is_constant(a) || is_constant(b);
        charge(by_constant ? double(a.size() + b.size()) : product_work(a, b), operator_pos);
        return product_of(a, b);
    }

    /// base^exponent by repeated squaring. The caller checked degree(base)·exponent ≤
    /// max_degree; every intermediate power then stays within that degree too.
    Terms raise(const Terms& base, int exponent, std::size_t operator_pos) {
        Terms result = constant_terms(1.0);
        Terms square = base;
        while (exponent > 0) {
            if (exponent & 1) result = multiply(result, square, operator_pos);
            exponent >>= 1;
            if (exponent > 0) square = multiply(square, square, operator_pos);
        }
        return result;
    }

    /// Adds the cost of an expansion step. The budget is about twice what the largest legitimate
    /// expansion, (1+x+y+z)^64, needs (≈ 0.1 s); strings that need more are rejected.
    void charge(double cost, std::size_t operator_pos) {
        work_ += cost;
        if (work_ > max_work) fail_at("expanding the polynomial takes too much work (too many terms)", operator_pos);
    }

    void check_degree(int degree, std::size_t operator_pos) const {
        if (degree > Polynomial::max_degree)
            fail_at("degree " + std::to_string(degree) + " exceeds the maximum " +
                        std::to_string(Polynomial::max_degree),
                    operator_pos);
    }

    /// Called when a complete sub-expression is followed by something that cannot continue it.
    [[noreturn]] void complain_about_leftover() const {
        const char c = peek();
        if (c == ')') fail_here("unmatched ')'");
        if (is_digit(c) || c == '.' || is_letter(c) || c == '(')
            fail_here("missing operator before " + describe(pos_) +
                      " (implicit multiplication is not supported: write 2*x)");
        fail_here("unexpected " + describe(pos_));
    }

    std::string describe(std::size_t pos) const {
        const unsigned char c = static_cast<unsigned char>(text_[pos]);
        if (c >= 0x20 && c < 0x7f) return "'" + std::string(1, static_cast<char>(c)) + "'";
        static const char* hex = "0123456789abcdef";
        return std::string("byte 0x") + hex[c >> 4] + hex[c & 15];
    }

    [[noreturn]] void fail_here(const std::string& problem) const { fail_at(problem, pos_); }

    [[noreturn]] void fail_at(const std::string& problem, std::size_t position) const {
        throw Error("polynomial '" + echo(text_) + "': " + problem + " at position " + std::to_string(position));
    }

    void skip_spaces() {
        while (!at_end() && is_space(peek())) ++pos_;
    }
    bool at_end() const { return pos_ >= text_.size(); }
    char peek() const { return text_[pos_]; }

    const std::string& text_;
    std::size_t pos_ = 0;
    int depth_ = 0;
    double work_ = 0.0;
};

/// Writes v with the shortest decimal form that reads back to the same double.
std::string format_number(double v) {
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
    return std::string(buffer, result.ptr);
}

std::string format_monomial_variables(const Monomial& m) {
    std::string text;
    const int exponents[3] = {m.ex, m.ey, m.ez};
    for (int axis = 0; axis < 3; ++axis) {
        if (exponents[axis] == 0) continue;
        if (!text.empty()) text += '*';
        text += static_cast<char>('x' + axis);
        if (exponents[axis] > 1) text += '^' + std::to_string(exponents[axis]);
    }
    return text;
}

}  // namespace

Polynomial::Polynomial(std::vector<Monomial> canonical_monomials) : monomials_(std::move(canonical_monomials)) {
    degree_ = degree_of(monomials_);
    for (int axis = 0; axis < 3; ++axis) max_exponent_[axis] = max_exponent_of(monomials_, axis);
}

Polynomial Polynomial::parse(const std::string& text) {
    Terms terms = Parser(text).parse_all();
    for (const Monomial& m : terms) {
        if (!std::isfinite(m.coefficient))
            throw Error("polynomial '" + echo(text) + "': a coefficient overflows when the polynomial is expanded");
    }
    return Polynomial(std::move(terms));
}

Polynomial Polynomial::from_monomials(std::vector<Monomial> monomials) {
    for (const Monomial& m : monomials) {
        if (m.ex < 0 || m.ey < 0 || m.ez < 0) throw Error("polynomial: negative exponent in a monomial");
        if (total_degree(m) > max_degree)
            throw Error("polynomial: degree " + std::to_string(total_degree(m)) + " exceeds the maximum " +
                        std::to_string(max_degree));
        if (!std::isfinite(m.coefficient)) throw Error("polynomial: non-finite coefficient");
    }
    return Polynomial(canonicalize(std::move(monomials)));
}

namespace detail {

// Kept out of line so that value() and digitize() execute the very same instructions.
[[gnu::noinline]] void evaluate_row(const Polynomial& f, const double* y_powers, const double* z_powers,
                                    const double* x_powers, std::size_t row_length, double* sums) {
    for (std::size_t i = 0; i < row_length; ++i) sums[i] = 0.0;
    for (const Monomial& m : f.monomials()) {
        const double weight = row_weight(m, y_powers, z_powers);
        const double* x_power = x_powers + static_cast<std::size_t>(m.ex) * row_length;
        for (std::size_t i = 0; i < row_length; ++i) sums[i] += weight * x_power[i];
    }
}

}  // namespace detail

double Polynomial::value(const Eigen::Vector3d& p) const {
    double px[detail::power_table_size], py[detail::power_table_size], pz[detail::power_table_size];
    detail::fill_powers(p.x(), max_exponent_[0], px);
    detail::fill_powers(p.y(), max_exponent_[1], py);
    detail::fill_powers(p.z(), max_exponent_[2], pz);
    double sum;
    detail::evaluate_row(*this, py, pz, px, 1, &sum);
    return sum;
}

Eigen::Vector3d Polynomial::gradient(const Eigen::Vector3d& p) const {
    double px[detail::power_table_size], py[detail::power_table_size], pz[detail::power_table_size];
    detail::fill_powers(p.x(), max_exponent_[0], px);
    detail::fill_powers(p.y(), max_exponent_[1], py);
    detail::fill_powers(p.z(), max_exponent_[2], pz);
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (const Monomial& m : monomials_) {
        const double c = m.coefficient;
        if (m.ex > 0) g.x() += c * m.ex * px[m.ex - 1] * py[m.ey] * pz[m.ez];
        if (m.ey > 0) g.y() += c * m.ey * px[m.ex] * py[m.ey - 1] * pz[m.ez];
        if (m.ez > 0) g.z() += c * m.ez * px[m.ex] * py[m.ey] * pz[m.ez - 1];
    }
    return g;
}

Eigen::Matrix3d Polynomial::hessian(const Eigen::Vector3d& p) const {
    double pw[3][detail::power_table_size];
    for (int axis = 0; axis < 3; ++axis) detail::fill_powers(p[axis], max_exponent_[axis], pw[axis]);
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    for (const Monomial& m : monomials_) {
        const int e[3] = {m.ex, m.ey, m.ez};
        for (int a = 0; a < 3; ++a) {
            for (int b = a; b < 3; ++b) {
                // ∂²/∂a∂b of c·Π x_k^e_k: lower exponent a (and b) by one, times the factors
                // e_a·e_b, or e_a·(e_a−1) on the diagonal.
                int d[3] = {e[0], e[1], e[2]};
                const double factor = (a == b) ? double(e[a]) * (e[a] - 1) : double(e[a]) * e[b];
                if (factor == 0.0) continue;
                d[a] -= 1;
                d[b] -= 1;
                h(a, b) += m.coefficient * factor * pw[0][d[0]] * pw[1][d[1]] * pw[2][d[2]];
            }
        }
    }
    h(1, 0) = h(0, 1);
    h(2, 0) = h(0, 2);
    h(2, 1) = h(1, 2);
    return h;
}

std::string Polynomial::to_string() const {
    if (monomials_.empty()) return "0";
    std::string text;
    for (const Monomial& m : monomials_) {
        const bool negative = m.coefficient < 0.0;
        const double magnitude = std::abs(m.coefficient);
        if (text.empty()) {
            if (negative) text += '-';
        } else {
            text += negative ? " - " : " + ";
        }
        const std::string variables = format_monomial_variables(m);
        if (variables.empty()) {
            text += format_number(magnitude);
        } else if (magnitude == 1.0) {
            text += variables;
        } else {
            text += format_number(magnitude) + "*" + variables;
        }
    }
    return text;
}

}  // namespace dsreg
