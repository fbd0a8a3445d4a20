// dsreg — error statistics, log-log slopes and geometric ranges of grid steps.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"

namespace dsreg {

ErrorStats ErrorStats::scaled(double factor) const {
    ErrorStats s = *this;
    s.mean *= factor;
    s.l2 *= factor;
    s.linf *= factor;
    s.p95 *= factor;
    return s;
}

ErrorStats error_stats(std::vector<double> errors) {
    ErrorStats s;
    if (errors.empty()) return s;
    s.count = std::int64_t(errors.size());
    double sum = 0, sum_squares = 0;
    for (double e : errors) {
        sum += e;
        sum_squares += e * e;
    }
    s.mean = sum / double(s.count);
    s.l2 = std::sqrt(sum_squares / double(s.count));
    // Nearest rank: the ⌈0.95·n⌉-th smallest value (1-based).
    const std::size_t rank = std::size_t(std::ceil(0.95 * double(s.count)));
    const std::size_t index = std::max<std::size_t>(rank, 1) - 1;
    std::nth_element(errors.begin(), errors.begin() + std::ptrdiff_t(index), errors.end());
    s.p95 = errors[index];
    s.linf = *std::max_element(errors.begin() + std::ptrdiff_t(index), errors.end());
    return s;
}

double log_log_slope(const std::vector<double>& x, const std::vector<double>& y) {
    std::vector<double> lx, ly;
    for (std::size_t i = 0; i < std::min(x.size(), y.size()); ++i) {
        if (x[i] > 0 && y[i] > 0 && std::isfinite(x[i]) && std::isfinite(y[i])) {
            lx.push_back(std::log(x[i]));
            ly.push_back(std::log(y[i]));
        }
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    if (lx.size() < 2) return nan;
    double mx = 0, my = 0;
    for (std::size_t i = 0; i < lx.size(); ++i) mx += lx[i], my += ly[i];
    mx /= double(lx.size());
    my /= double(ly.size());
    double sxx = 0, sxy = 0;
    for (std::size_t i = 0; i < lx.size(); ++i) {
        sxx += (lx[i] - mx) * (lx[i] - mx);
        sxy += (lx[i] - mx) * (ly[i] - my);
    }
    return sxx > 0 ? sxy / sxx : nan;
}

std::vector<double> geometric_steps(double largest, double smallest, int count) {
    std::ostringstream range;
    range << largest << ":" << smallest << ":" << count;
    if (!std::isfinite(largest) || !std::isfinite(smallest) || !(smallest > 0))
        throw Error("grid steps " + range.str() + ": MAX and MIN must be finite and positive");
    if (largest < smallest) throw Error("grid steps " + range.str() + ": MAX must not be smaller than MIN");
    if (count < 1 || (count == 1 && largest != smallest))
        throw Error("grid steps " + range.str() + ": COUNT must be at least 2");
    std::vector<double> steps(std::size_t(count), largest);
    for (int i = 1; i < count; ++i)
        steps[std::size_t(i)] = largest * std::pow(smallest / largest, double(i) / double(count - 1));
    steps.back() = smallest;
    return steps;
}

}  // namespace dsreg
