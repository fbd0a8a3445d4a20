#include "convergence_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "dsreg/text.hpp"
#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/regularization.hpp"
#include "eval_command.hpp"

namespace dsreg::cli {

namespace {

struct ConvergenceCommandOptions {
    TruthShapeOptions truth;
    std::string h_range;
    std::string out_dir;
    std::string normals = "exact";
    double radius_k = 3.0;
    std::string ii_kernel = "biweight";
    bool ii_extrapolate = false;
    double alpha_k = 1e-5;
    double beta = 1.0;
    double gamma = 0.0;
    int connectivity = 26;
    std::string solver = "auto";
    std::optional<double> wall_margin;
    bool quiet = false;
};

struct StepRange {
    double largest, smallest;
    int count;
};

double parse_number(const std::string& text, const std::string& whole) {
    if (const std::optional<double> value = parse_whole_number(text)) return *value;
    throw Error("--h " + whole + ": '" + text + "' is not a number (expected MAX:MIN:COUNT, e.g. 0.2:0.006:12)");
}

/// "MAX:MIN:COUNT" → the geometric range (checked by geometric_steps).
std::vector<double> parse_step_range(const std::string& text) {
    std::vector<std::string> parts;
    std::stringstream stream(text);
    for (std::string part; std::getline(stream, part, ':');) parts.push_back(part);
    if (parts.size() != 3 || text.back() == ':')
        throw Error("--h " + text + ": expected MAX:MIN:COUNT (geometric range), e.g. 0.2:0.006:12");
    const double largest = parse_number(parts[0], text), smallest = parse_number(parts[1], text);
    const double count = parse_number(parts[2], text);
    if (count != std::floor(count) || count < 1 || count > 1000)
        throw Error("--h " + text + ": COUNT must be a whole number from 2 to 1000");
    try {
        return geometric_steps(largest, smallest, int(count));
    } catch (const Error& e) {
        throw Error("--h: " + std::string(e.what()));
    }
}

/// The output folder must be a folder or creatable: its nearest existing ancestor is a folder.
void check_output_dir(const std::string& dir) {
    namespace fs = std::filesystem;
    if (dir.empty()) throw Error("--out: give a folder");
    fs::path path = fs::absolute(dir);
    if (fs::exists(path)) {
        if (!fs::is_directory(path)) throw Error("--out " + dir + ": exists and is not a folder");
        return;
    }
    for (fs::path parent = path.parent_path(); !parent.empty(); parent = parent.parent_path()) {
        if (fs::exists(parent)) {
            if (!fs::is_directory(parent)) throw Error("--out " + dir + ": " + parent.string() + " is not a folder");
            return;
        }
        if (parent == parent.root_path()) break;
    }
}

/// Default region: a quarter of the smallest half-extent of the box along the clipped axes.
double default_wall_margin(const ImplicitShape& shape) {
    double half = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a)
        if (shape.clipped[std::size_t(a)]) half = std::min(half, 0.5 * (shape.upper[a] - shape.lower[a]));
    return std::isfinite(half) ? 0.25 * half : 0.0;
}

void check_grid_size(const ImplicitShape& shape, double h) {
    const Eigen::Vector3d cells = (shape.upper - shape.lower) / h + Eigen::Vector3d::Constant(3);
    constexpr double max_voxels = 17179869184.0;  // digitize()'s limit, 2^34
    if (cells.prod() > max_voxels)
        throw Error("--h: the smallest step " + format("%g", h) + " needs about " + format("%.3g", cells.prod()) +
                    " voxels for " + shape.name + ", more than 2^34");
}

std::string csv_text(const std::vector<ConvergenceStep>& steps) {
    std::ostringstream out;
    out << "h,faces,vertices,faces_evaluated,vertices_evaluated,radius,alpha,normal_l2,normal_linf,p_l2,p_linf,"
           "pstar_l2,pstar_linf,ratio_l2,ratio_linf,closer_share,relative_residual,seconds\n";
    auto g = [](double x) { return format("%.10g", x); };
    for (const ConvergenceStep& s : steps) {
        out << g(s.h) << ',' << s.faces << ',' << s.vertices << ',' << s.faces_evaluated << ',' << s.vertices_evaluated
            << ',' << g(s.radius) << ',' << g(s.alpha) << ',' << g(s.normal.l2) << ',' << g(s.normal.linf) << ','
            << g(s.p.l2) << ',' << g(s.p.linf) << ',' << g(s.pstar.l2) << ',' << g(s.pstar.linf) << ','
            << g(s.ratio.l2) << ',' << g(s.ratio.linf) << ',' << g(s.closer_share) << ',' << g(s.relative_residual)
            << ',' << format("%.3f", s.seconds) << '\n';
    }
    return out.str();
}

/// The shape as the plot title names it: a plane's polynomial is too long for a title.
std::string short_shape_name(const ConvergenceCommandOptions& o, const ImplicitShape& shape) {
    if (o.truth.shape != "plane" || o.truth.plane_normal.size() != 3) return shape.name;
    std::ostringstream s;
    s << "plane n·x = " << format("%g", o.truth.plane_offset) << ", n ∝ (" << format("%.4g", o.truth.plane_normal[0])
      << ", " << format("%.4g", o.truth.plane_normal[1]) << ", " << format("%.4g", o.truth.plane_normal[2]) << ") in [-"
      << format("%g", o.truth.box ? *o.truth.box : 1.0) << ", " << format("%g", o.truth.box ? *o.truth.box : 1.0) << "]³";
    return s.str();
}

std::string describe_run(const ConvergenceCommandOptions& o, const ImplicitShape& shape, const std::vector<double>& steps) {
    std::ostringstream s;
    s << short_shape_name(o, shape) << ", " << (o.normals == "ii" ? "II normals (" + o.ii_kernel + (o.ii_extrapolate ? ", extrapolated" : "") + ") r = " + format("%g", o.radius_k) + "·h^(1/3)" : "exact normals")
      << ", alpha = " << format("%g", o.alpha_k) << "·h², beta = " << format("%g", o.beta) << ", gamma = "
      << format("%g", o.gamma) << "; " << steps.size() << " steps h = " << format("%g", steps.front()) << " → "
      << format("%g", steps.back());
    return s.str();
}

std::string slope(double value) { return std::isfinite(value) ? format("%6.2f", value) : "   n/a"; }

void print_summary(std::ostream& out, const std::string& description, const std::vector<ConvergenceStep>& steps) {
    const ConvergenceSlopes slopes = convergence_slopes(steps);
    out << description << "\n\n";
    out << "  curve (least-squares slope of log error vs log h)   L2      Linf\n";
    out << "  normals        |u* - u|                          " << slope(slopes.normal.l2) << "  " << slope(slopes.normal.linf) << '\n';
    out << "  digital        |p - xi(p)|                       " << slope(slopes.p.l2) << "  " << slope(slopes.p.linf) << '\n';
    out << "  regularized    |p* - xi(p*)|                     " << slope(slopes.pstar.l2) << "  " << slope(slopes.pstar.linf) << '\n';
    out << "  ratio          |p* - xi(p*)| / |p - xi(p)|       " << slope(slopes.ratio.l2) << "  " << slope(slopes.ratio.linf) << "\n\n";

    int closer_l2 = 0, closer_linf = 0;
    double worst_p_over_h = 0, worst_pstar_over_h = 0, min_ratio = 1e300, max_ratio = 0;
    for (const ConvergenceStep& s : steps) {
        closer_l2 += s.pstar.l2 < s.p.l2 ? 1 : 0;
        closer_linf += s.pstar.linf < s.p.linf ? 1 : 0;
        worst_p_over_h = std::max(worst_p_over_h, s.p.linf / s.h);
        worst_pstar_over_h = std::max(worst_pstar_over_h, s.pstar.linf / s.h);
        min_ratio = std::min(min_ratio, s.ratio.l2);
        max_ratio = std::max(max_ratio, s.ratio.l2);
    }
    const std::size_t n = steps.size();
    out << "  p* closer to the surface than p: L2 at " << closer_l2 << " of " << n << " steps, Linf at " << closer_linf
        << " of " << n << " steps; L2 ratio p*/p from " << format("%.3g", min_ratio) << " to " << format("%.3g", max_ratio)
        << '\n';
    out << "  largest Linf distance over all steps: p " << format("%.3f", worst_p_over_h) << "·h, p* "
        << format("%.3f", worst_pstar_over_h) << "·h (Gauss digitization bound sqrt(3)/2·h = 0.866·h)\n";
}

void run(const ConvergenceCommandOptions& o) {
    const ImplicitShape shape = make_truth_shape(o.truth);
    const std::vector<double> steps = parse_step_range(o.h_range);
    check_output_dir(o.out_dir);
    check_grid_size(shape, steps.back());
    if (!(o.radius_k > 0) || !std::isfinite(o.radius_k)) throw Error("--radius-k must be positive");
    if (!(o.alpha_k > 0) || !std::isfinite(o.alpha_k)) throw Error("--alpha-k must be positive (alpha = A·h² > 0)");
    if (o.wall_margin && (!(*o.wall_margin >= 0) || !std::isfinite(*o.wall_margin)))
        throw Error("--wall-margin must be non-negative");
    RegularizationWeights weights;
    weights.alpha = o.alpha_k * steps.back() * steps.back();
    weights.beta = o.beta;
    weights.gamma = o.gamma;
    validate_weights(weights, 0, 0);

    ConvergenceOptions options;
    options.normals = o.normals == "ii" ? InputNormalField::IntegralInvariant : InputNormalField::Exact;
    options.radius_k = o.radius_k;
    options.ii_kernel = parse_integral_invariant_kernel(o.ii_kernel);
    options.ii_extrapolate = o.ii_extrapolate;
    options.alpha_k = o.alpha_k;
    options.beta = o.beta;
    options.gamma = o.gamma;
    options.connectivity = o.connectivity == 6 ? Connectivity::Six : Connectivity::TwentySix;
    options.solver.kind = parse_solver_kind(o.solver);
    options.wall_margin = o.wall_margin ? *o.wall_margin : default_wall_margin(shape);

    std::vector<ConvergenceStep> results;
    for (std::size_t i = 0; i < steps.size(); ++i) {
        if (!o.quiet) std::cerr << "convergence: [" << i + 1 << "/" << steps.size() << "] h = " << format("%.4g", steps[i]) << " ..." << std::flush;
        const ConvergenceStep step = run_convergence_step(shape, steps[i], options);
        results.push_back(step);
        if (!o.quiet)
            std::cerr << " " << step.faces << " faces; L2 |p-xi(p)| " << format("%.3g", step.p.l2) << ", |p*-xi(p*)| "
                      << format("%.3g", step.pstar.l2) << ", |u*-u| " << format("%.3g", step.normal.l2) << "; residual "
                      << format("%.1e", step.relative_residual) << "; " << format("%.2f", step.seconds) << " s\n";
    }

    const std::string description = describe_run(o, shape, steps);
    const std::string csv = csv_text(results);
    const std::string svg = convergence_plot_svg(description, results);
    const std::filesystem::path dir(o.out_dir);
    std::error_code error;
    std::filesystem::create_directories(dir, error);
    if (error) throw Error("--out " + o.out_dir + ": cannot create the folder: " + error.message());
    const std::string csv_path = (dir / "convergence.csv").string(), svg_path = (dir / "convergence.svg").string();
    write_file_atomically(csv_path, [&](std::ostream& out) { out << csv; });
    write_file_atomically(svg_path, [&](std::ostream& out) { out << svg; });

    print_summary(std::cout, description, results);
    std::cout << "  wrote " << csv_path << " and " << svg_path << '\n';
}

}  // namespace

void add_convergence_command(CLI::App& app) {
    auto options = std::make_shared<ConvergenceCommandOptions>();
    CLI::App* cmd = app.add_subcommand(
        "convergence", "Multigrid convergence experiment (paper Fig. 7): for each grid step h, digitize the shape, "
                       "regularize with alpha = A·h², and measure |u*-u|, |p-xi(p)|, |p*-xi(p*)| in L2 and Linf");
    add_truth_shape_options(*cmd, options->truth)->required();
    cmd->add_option("--h", options->h_range, "Grid steps MAX:MIN:COUNT, geometric (e.g. 0.2:0.006:12)")->required();
    cmd->add_option("--out", options->out_dir, "Output folder (created if missing): convergence.csv, convergence.svg")
        ->required();
    cmd->add_option("--normals", options->normals,
                    "Input field u: exact (true normals of the solid, box walls included) or ii (integral invariants)")
        ->check(CLI::IsMember({"exact", "ii"}))
        ->capture_default_str();
    cmd->add_option("--radius-k", options->radius_k, "II radius r = K·h^(1/3) (physical units; 3 suits shapes about 10 across such as goursat, 1 the unit "
                    "sphere and the plane in [-1,1]^3, as in docs/convergence.md)")->capture_default_str();
    cmd->add_option("--ii-kernel", options->ii_kernel,
                    "Weights of the II ball: biweight (1 - d^2/r^2)^2 or ball (uniform, the paper's)")
        ->check(CLI::IsMember({"ball", "biweight"}))
        ->capture_default_str();
    cmd->add_flag("--ii-extrapolate", options->ii_extrapolate,
                  "II at r and r/sqrt(2) combined as 2 n(r/sqrt(2)) - n(r) (removes the r^2 bias)");
    cmd->add_option("--alpha-k", options->alpha_k, "Data attachment alpha = A·h²")->capture_default_str();
    cmd->add_option("--beta", options->beta, "Weight of normal alignment")->capture_default_str();
    cmd->add_option("--gamma", options->gamma, "Weight of fairness")->capture_default_str();
    cmd->add_option("--connectivity", options->connectivity, "Object connectivity, 6 or 26")
        ->check(CLI::IsMember({6, 26}))
        ->capture_default_str();
    cmd->add_option("--solver", options->solver, "Linear solver (auto picks cholmod for the tiny alpha of Fig. 7)")->check(CLI::IsMember(solver_names()))->capture_default_str();
    cmd->add_option("--wall-margin", options->wall_margin,
                    "Leave out vertices and faces closer than this to a clipped box face (physical units; default: a "
                    "quarter of the box half-size for clipped shapes such as 'plane', else 0)");
    cmd->add_flag("-q,--quiet", options->quiet, "No progress lines on stderr");
    cmd->callback([options] { run(*options); });
}

}  // namespace dsreg::cli
