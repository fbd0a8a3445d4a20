// dsreg — small SVG writer for log-log plots (the convergence figures), no dependency.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "dsreg/evaluation.hpp"

namespace dsreg {
namespace {

// Layout of one panel, in SVG user units (pixels).
constexpr double panel_width = 400, panel_height = 300;
constexpr double margin_left = 72, margin_right = 16, margin_top = 34, margin_bottom = 48;
constexpr double title_height = 34;

const char* const curve_colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"};

std::string escape(const std::string& text) {
    std::string out;
    for (char c : text) {
        if (c == '&') out += "&amp;";
        else if (c == '<') out += "&lt;";
        else if (c == '>') out += "&gt;";
        else if (c == '"') out += "&quot;";
        else out += c;
    }
    return out;
}

std::string number(double x) {
    char text[32];
    std::snprintf(text, sizeof text, "%.2f", x);
    return text;
}

/// A log10 interval [low, high] of an axis.
struct LogRange {
    double low, high;
};

/// log10 range of the positive finite values, widened by 4% on each side (half a decade on each
/// side when all values are equal). {0, 1} when there is no such value.
LogRange log_range(const std::vector<double>& values) {
    double low = std::numeric_limits<double>::infinity(), high = -low;
    for (double v : values)
        if (v > 0 && std::isfinite(v)) low = std::min(low, std::log10(v)), high = std::max(high, std::log10(v));
    if (!(low <= high)) return {0, 1};
    if (high - low < 1e-9) return {low - 0.5, high + 0.5};
    const double pad = 0.04 * (high - low);
    return {low - pad, high + pad};
}

/// Maps log10(value) of a range onto [from, to] (pixels).
double to_pixel(double value, const LogRange& r, double from, double to) {
    return from + (std::log10(value) - r.low) / (r.high - r.low) * (to - from);
}

/// Tick values: the powers of ten in range; with fewer than two of them, 2·10^k and 5·10^k too.
std::vector<double> tick_values(const LogRange& r) {
    std::vector<double> ticks;
    for (int k = int(std::floor(r.low)); k <= int(std::ceil(r.high)); ++k)
        if (k >= r.low && k <= r.high) ticks.push_back(std::pow(10.0, k));
    if (ticks.size() < 2) {
        for (int k = int(std::floor(r.low)); k <= int(std::ceil(r.high)); ++k)
            for (double m : {2.0, 5.0}) {
                const double t = m * std::pow(10.0, k);
                if (std::log10(t) >= r.low && std::log10(t) <= r.high) ticks.push_back(t);
            }
        std::sort(ticks.begin(), ticks.end());
    }
    return ticks;
}

/// True for values written as a plain decimal (0.01 … 9999).
bool is_moderate(double value) {
    const double decade = std::floor(std::log10(value) + 1e-9);
    return decade >= -2 && decade <= 3;
}

/// A short decimal when `decimal` (the caller passes it for a whole axis, so that one axis never
/// mixes "0.01" with "10⁻³"); otherwise 10^k (superscript) for powers of ten, else m×10^k.
std::string tick_label(double value, bool decimal) {
    if (decimal) {
        std::ostringstream s;
        s << value;
        return s.str();
    }
    const double k = std::round(std::log10(value));
    if (std::abs(std::pow(10.0, k) - value) < 1e-9 * value) {
        const std::string exponent = k < 0 ? "\u2212" + std::to_string(int(-k)) : std::to_string(int(k));
        return "10<tspan dy=\"-6\" font-size=\"9\">" + exponent + "</tspan>";
    }
    const double mantissa = std::round(value / std::pow(10.0, std::floor(std::log10(value))));
    const double exponent = std::floor(std::log10(value));
    std::ostringstream s;
    s << mantissa << "\u00d710<tspan dy=\"-6\" font-size=\"9\">"
      << (exponent < 0 ? "\u2212" + std::to_string(int(-exponent)) : std::to_string(int(exponent))) << "</tspan>";
    return s.str();
}

/// Whether every tick of an axis can be written as a plain decimal.
bool decimal_axis(const std::vector<double>& ticks) { return std::all_of(ticks.begin(), ticks.end(), is_moderate); }

class PanelWriter {
public:
    PanelWriter(std::ostringstream& out, double x0, double y0, const LogRange& x_range, int id)
        : out_(out), left_(x0 + margin_left), right_(x0 + panel_width - margin_right), top_(y0 + margin_top),
          bottom_(y0 + panel_height - margin_bottom), x0_(x0), y0_(y0), x_range_(x_range), id_(id) {}

    void write(const PlotPanel& panel, const std::string& x_label) {
        std::vector<double> all_y;
        for (const PlotCurve& c : panel.curves) all_y.insert(all_y.end(), c.y.begin(), c.y.end());
        y_range_ = log_range(all_y);
        out_ << "<g>\n";
        write_frame_and_ticks(panel, x_label);
        out_ << "<clipPath id=\"clip" << id_ << "\"><rect x=\"" << number(left_) << "\" y=\"" << number(top_)
             << "\" width=\"" << number(right_ - left_) << "\" height=\"" << number(bottom_ - top_) << "\"/></clipPath>\n";
        if (panel.reference_slope_one && !panel.curves.empty()) write_slope_one_guide(panel.curves.front());
        for (std::size_t c = 0; c < panel.curves.size(); ++c)
            write_curve(panel.curves[c], curve_colours[c % (sizeof curve_colours / sizeof *curve_colours)], int(c));
        write_legend(panel);
        out_ << "</g>\n";
    }

private:
    double px(double x) const { return to_pixel(x, x_range_, left_, right_); }
    double py(double y) const { return to_pixel(y, y_range_, bottom_, top_); }

    void write_frame_and_ticks(const PlotPanel& panel, const std::string& x_label) {
        const std::vector<double> x_ticks = tick_values(x_range_), y_ticks = tick_values(y_range_);
        const bool x_decimal = decimal_axis(x_ticks), y_decimal = decimal_axis(y_ticks);
        for (double t : x_ticks) {
            const double x = px(t);
            out_ << "<line x1=\"" << number(x) << "\" y1=\"" << number(top_) << "\" x2=\"" << number(x) << "\" y2=\""
                 << number(bottom_) << "\" stroke=\"#e4e4e4\"/>\n";
            out_ << "<text x=\"" << number(x) << "\" y=\"" << number(bottom_ + 16) << "\" text-anchor=\"middle\">"
                 << tick_label(t, x_decimal) << "</text>\n";
        }
        for (double t : y_ticks) {
            const double y = py(t);
            out_ << "<line x1=\"" << number(left_) << "\" y1=\"" << number(y) << "\" x2=\"" << number(right_) << "\" y2=\""
                 << number(y) << "\" stroke=\"#e4e4e4\"/>\n";
            out_ << "<text x=\"" << number(left_ - 6) << "\" y=\"" << number(y + 4) << "\" text-anchor=\"end\">"
                 << tick_label(t, y_decimal) << "</text>\n";
        }
        write_minor_ticks();
        out_ << "<rect x=\"" << number(left_) << "\" y=\"" << number(top_) << "\" width=\"" << number(right_ - left_)
             << "\" height=\"" << number(bottom_ - top_) << "\" fill=\"none\" stroke=\"#444\"/>\n";
        out_ << "<text x=\"" << number((left_ + right_) / 2) << "\" y=\"" << number(y0_ + 20)
             << "\" text-anchor=\"middle\" font-weight=\"bold\">" << escape(panel.title) << "</text>\n";
        out_ << "<text x=\"" << number((left_ + right_) / 2) << "\" y=\"" << number(bottom_ + 36)
             << "\" text-anchor=\"middle\">" << escape(x_label) << "</text>\n";
        const double label_x = x0_ + 16, label_y = (top_ + bottom_) / 2;
        out_ << "<text x=\"" << number(label_x) << "\" y=\"" << number(label_y) << "\" text-anchor=\"middle\" transform=\"rotate(-90 "
             << number(label_x) << " " << number(label_y) << ")\">" << escape(panel.y_label) << "</text>\n";
    }

    /// Short unlabelled marks at 2…9 × 10^k inside the frame, on both axes.
    void write_minor_ticks() {
        auto marks = [](const LogRange& r) {
            std::vector<double> values;
            for (int k = int(std::floor(r.low)); k <= int(std::ceil(r.high)); ++k)
                for (int m = 2; m <= 9; ++m) {
                    const double v = m * std::pow(10.0, k);
                    if (std::log10(v) >= r.low && std::log10(v) <= r.high) values.push_back(v);
                }
            return values;
        };
        for (double t : marks(x_range_))
            out_ << "<line x1=\"" << number(px(t)) << "\" y1=\"" << number(bottom_) << "\" x2=\"" << number(px(t))
                 << "\" y2=\"" << number(bottom_ - 4) << "\" stroke=\"#444\"/>\n";
        for (double t : marks(y_range_))
            out_ << "<line x1=\"" << number(left_) << "\" y1=\"" << number(py(t)) << "\" x2=\"" << number(left_ + 4)
                 << "\" y2=\"" << number(py(t)) << "\" stroke=\"#444\"/>\n";
    }

    /// A dashed line of slope 1 through half the value of the first curve at its largest x.
    void write_slope_one_guide(const PlotCurve& curve) {
        double anchor_x = 0, anchor_y = 0;
        for (std::size_t i = 0; i < std::min(curve.x.size(), curve.y.size()); ++i)
            if (curve.x[i] > anchor_x && curve.y[i] > 0 && std::isfinite(curve.y[i])) anchor_x = curve.x[i], anchor_y = curve.y[i];
        if (anchor_x <= 0) return;
        const double low_x = std::pow(10.0, x_range_.low), high_x = std::pow(10.0, x_range_.high);
        const double scale = 0.5 * anchor_y / anchor_x;
        out_ << "<g clip-path=\"url(#clip" << id_ << ")\"><line x1=\"" << number(px(low_x)) << "\" y1=\""
             << number(py(scale * low_x)) << "\" x2=\"" << number(px(high_x)) << "\" y2=\"" << number(py(scale * high_x))
             << "\" stroke=\"#888\" stroke-dasharray=\"5 4\"/></g>\n";
    }

    void write_curve(const PlotCurve& curve, const char* colour, int index) {
        std::ostringstream path;
        bool first = true;
        std::vector<std::pair<double, double>> points;
        for (std::size_t i = 0; i < std::min(curve.x.size(), curve.y.size()); ++i)
            if (curve.x[i] > 0 && curve.y[i] > 0 && std::isfinite(curve.x[i]) && std::isfinite(curve.y[i]))
                points.emplace_back(px(curve.x[i]), py(curve.y[i]));
        for (const auto& [x, y] : points) {
            path << (first ? "M" : " L") << number(x) << " " << number(y);
            first = false;
        }
        if (points.empty()) return;
        out_ << "<g clip-path=\"url(#clip" << id_ << ")\">\n<path d=\"" << path.str() << "\" fill=\"none\" stroke=\"" << colour
             << "\" stroke-width=\"1.8\"/>\n";
        for (const auto& [x, y] : points) write_marker(x, y, colour, index);
        out_ << "</g>\n";
    }

    void write_marker(double x, double y, const char* colour, int index) {
        if (index % 2 == 0)
            out_ << "<circle cx=\"" << number(x) << "\" cy=\"" << number(y) << "\" r=\"3.2\" fill=\"" << colour << "\"/>\n";
        else
            out_ << "<rect x=\"" << number(x - 3) << "\" y=\"" << number(y - 3) << "\" width=\"6\" height=\"6\" fill=\"" << colour
                 << "\"/>\n";
    }

    /// Top-left corner of the legend box: the corner of the plot that hides the least of the
    /// curves (their markers, and their segments sampled every few pixels); the first corner in
    /// the order top-left, top-right, bottom-right, bottom-left on a tie.
    std::pair<double, double> legend_corner(const PlotPanel& panel, double width, double height) const {
        std::vector<std::pair<double, double>> samples;
        for (const PlotCurve& c : panel.curves) {
            std::vector<std::pair<double, double>> points;
            for (std::size_t i = 0; i < std::min(c.x.size(), c.y.size()); ++i)
                if (c.x[i] > 0 && c.y[i] > 0 && std::isfinite(c.x[i]) && std::isfinite(c.y[i]))
                    points.emplace_back(px(c.x[i]), py(c.y[i]));
            for (std::size_t i = 0; i < points.size(); ++i) {
                for (int m = 0; m < 4; ++m) samples.push_back(points[i]);  // a marker weighs more than a line
                if (i + 1 == points.size()) break;
                const auto [x0, y0] = points[i];
                const auto [x1, y1] = points[i + 1];
                const int pieces = std::max(1, int(std::hypot(x1 - x0, y1 - y0) / 5.0));
                for (int k = 1; k < pieces; ++k)
                    samples.emplace_back(x0 + (x1 - x0) * k / pieces, y0 + (y1 - y0) * k / pieces);
            }
        }
        const std::pair<double, double> corners[] = {{left_ + 5, top_ + 4}, {right_ - 5 - width, top_ + 4},
                                                     {right_ - 5 - width, bottom_ - 4 - height}, {left_ + 5, bottom_ - 4 - height}};
        std::pair<double, double> best = corners[0];
        std::size_t fewest = std::numeric_limits<std::size_t>::max();
        for (const auto& [bx, by] : corners) {
            std::size_t hidden = 0;
            for (const auto& [x, y] : samples)
                hidden += (x >= bx - 4 && x <= bx + width + 4 && y >= by - 4 && y <= by + height + 4) ? 1 : 0;
            if (hidden < fewest) fewest = hidden, best = {bx, by};
        }
        return best;
    }

    void write_legend(const PlotPanel& panel) {
        const double rows = double(panel.curves.size()) + (panel.reference_slope_one ? 1.0 : 0.0);
        const double width = 150, height = 16 * rows + 4;
        const auto [box_x, box_y] = legend_corner(panel, width, height);
        out_ << "<rect x=\"" << number(box_x) << "\" y=\"" << number(box_y) << "\" width=\"" << number(width)
             << "\" height=\"" << number(height) << "\" fill=\"white\" fill-opacity=\"0.85\" stroke=\"#ccc\"/>\n";
        const double x = box_x + 5;
        double y = box_y + 16;
        for (std::size_t c = 0; c < panel.curves.size(); ++c, y += 16) {
            const char* colour = curve_colours[c % (sizeof curve_colours / sizeof *curve_colours)];
            out_ << "<line x1=\"" << number(x) << "\" y1=\"" << number(y - 4) << "\" x2=\"" << number(x + 18) << "\" y2=\""
                 << number(y - 4) << "\" stroke=\"" << colour << "\" stroke-width=\"1.8\"/>\n";
            write_marker(x + 9, y - 4, colour, int(c));
            out_ << "<text x=\"" << number(x + 24) << "\" y=\"" << number(y) << "\">" << escape(panel.curves[c].label)
                 << "</text>\n";
        }
        if (panel.reference_slope_one) {
            out_ << "<line x1=\"" << number(x) << "\" y1=\"" << number(y - 4) << "\" x2=\"" << number(x + 18) << "\" y2=\""
                 << number(y - 4) << "\" stroke=\"#888\" stroke-dasharray=\"5 4\"/>\n";
            out_ << "<text x=\"" << number(x + 24) << "\" y=\"" << number(y) << "\">O(h)</text>\n";
        }
    }

    std::ostringstream& out_;
    double left_, right_, top_, bottom_, x0_, y0_;
    LogRange x_range_, y_range_{0, 1};
    int id_;
};

std::string slope_text(double slope) {
    if (!std::isfinite(slope)) return "slope n/a";
    char text[32];
    std::snprintf(text, sizeof text, "slope %.2f", slope);
    return text;
}

PlotPanel norms_panel(const std::string& title, const std::vector<ConvergenceStep>& steps,
                      const ErrorNorms ConvergenceStep::*member, bool guide) {
    PlotPanel panel;
    panel.title = title;
    panel.y_label = guide ? "error (physical units)" : "ratio";
    panel.reference_slope_one = guide;
    PlotCurve l2, linf;
    for (const ConvergenceStep& s : steps) {
        l2.x.push_back(s.h), l2.y.push_back((s.*member).l2);
        linf.x.push_back(s.h), linf.y.push_back((s.*member).linf);
    }
    l2.label = "L2, " + slope_text(log_log_slope(l2.x, l2.y));
    linf.label = "L\u221e, " + slope_text(log_log_slope(linf.x, linf.y));
    panel.curves = {l2, linf};
    return panel;
}

}  // namespace

std::string log_log_plot_svg(const std::string& title, const std::string& x_label, const std::vector<PlotPanel>& panels,
                             int columns) {
    columns = std::max(1, columns);
    const int rows = std::max(1, int((panels.size() + std::size_t(columns) - 1) / std::size_t(columns)));
    const int used_columns = std::min<int>(columns, std::max<int>(1, int(panels.size())));
    const double width = used_columns * panel_width, height = title_height + rows * panel_height;
    std::vector<double> all_x;
    for (const PlotPanel& p : panels)
        for (const PlotCurve& c : p.curves) all_x.insert(all_x.end(), c.x.begin(), c.x.end());
    const LogRange x_range = log_range(all_x);

    std::ostringstream out;
    out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << number(width) << "\" height=\"" << number(height)
        << "\" viewBox=\"0 0 " << number(width) << " " << number(height)
        << "\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"11\">\n";
    out << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    // Bold Helvetica averages about 0.6 em per character: shrink a title that would not fit.
    std::size_t characters = 0;
    for (unsigned char c : title) characters += (c & 0xC0) != 0x80 ? 1 : 0;  // UTF-8 code points
    const double font_size = std::max(8.0, std::min(15.0, (width - 20) / (0.6 * double(std::max<std::size_t>(1, characters)))));
    out << "<text x=\"" << number(width / 2) << "\" y=\"22\" text-anchor=\"middle\" font-size=\"" << number(font_size)
        << "\" font-weight=\"bold\">" << escape(title) << "</text>\n";
    for (std::size_t i = 0; i < panels.size(); ++i) {
        const double x0 = double(int(i) % columns) * panel_width;
        const double y0 = title_height + double(int(i) / columns) * panel_height;
        PanelWriter(out, x0, y0, x_range, int(i)).write(panels[i], x_label);
    }
    out << "</svg>\n";
    return out.str();
}

std::string convergence_plot_svg(const std::string& title, const std::vector<ConvergenceStep>& steps) {
    const std::vector<PlotPanel> panels{
        norms_panel("normals: |u* \u2212 u|", steps, &ConvergenceStep::normal, true),
        norms_panel("digital surface: |p \u2212 \u03be(p)|", steps, &ConvergenceStep::p, true),
        norms_panel("regularized: |p* \u2212 \u03be(p*)|", steps, &ConvergenceStep::pstar, true),
        norms_panel("p* vs p: |p* \u2212 \u03be(p*)| / |p \u2212 \u03be(p)|", steps, &ConvergenceStep::ratio, false),
    };
    return log_log_plot_svg(title, "grid step h", panels, 2);
}

}  // namespace dsreg
