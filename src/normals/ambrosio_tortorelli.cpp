// Ambrosio–Tortorelli regularization of a normal vector field (see ambrosio_tortorelli.hpp).
#include "dsreg/ambrosio_tortorelli.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <string>

#include "at_linear_solver.hpp"
#include "dsreg/error.hpp"

namespace dsreg {

namespace {

using Clock = std::chrono::steady_clock;
using SparseMatrix = Eigen::SparseMatrix<double>;
using Edge = std::array<std::int32_t, 2>;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::string number(double x) {
    std::ostringstream text;
    text << x;
    return text.str();
}

void require_finite_positive(double value, const char* name) {
    if (!(value > 0) || !std::isfinite(value))
        throw Error(std::string("Ambrosio-Tortorelli: ") + name + " must be positive and finite (got " + number(value) + ")");
}

/// A symmetric matrix over the nodes of a graph with a fixed pattern (diagonal + one entry per
/// edge), lower triangle stored in compressed columns:
///   K = diag(node) + Σ_e [ edge_diagonal_e at (i,i) and (j,j), edge_off_e at (i,j) and (j,i) ].
/// Both AT matrices have this form: the u-matrix over the face graph, the v-matrix over the
/// vertex graph. The slots of every entry are found once; assembling only adds numbers.
class GraphMatrix {
public:
    GraphMatrix(std::int64_t node_count, const std::vector<Edge>& edges) : edges_(edges) {
        std::vector<Eigen::Triplet<double>> entries;
        entries.reserve(std::size_t(node_count) + edges.size());
        for (std::int64_t i = 0; i < node_count; ++i) entries.emplace_back(i, i, 0.0);
        for (const Edge& e : edges) entries.emplace_back(std::max(e[0], e[1]), std::min(e[0], e[1]), 0.0);
        matrix_.resize(node_count, node_count);
        matrix_.setFromTriplets(entries.begin(), entries.end());  // explicit zeros are kept
        matrix_.makeCompressed();
        diagonal_slot_.resize(std::size_t(node_count));
        for (std::int64_t j = 0; j < node_count; ++j) diagonal_slot_[std::size_t(j)] = slot(j, j);
        edge_slot_.resize(edges.size());
        for (std::size_t e = 0; e < edges.size(); ++e)
            edge_slot_[e] = slot(std::max(edges[e][0], edges[e][1]), std::min(edges[e][0], edges[e][1]));
    }

    void assemble(const Eigen::VectorXd& node, const Eigen::VectorXd& edge_diagonal, const Eigen::VectorXd& edge_off) {
        double* value = matrix_.valuePtr();
        std::fill(value, value + matrix_.nonZeros(), 0.0);
        for (std::size_t i = 0; i < diagonal_slot_.size(); ++i) value[diagonal_slot_[i]] += node[Eigen::Index(i)];
        for (std::size_t e = 0; e < edges_.size(); ++e) {
            value[diagonal_slot_[std::size_t(edges_[e][0])]] += edge_diagonal[Eigen::Index(e)];
            value[diagonal_slot_[std::size_t(edges_[e][1])]] += edge_diagonal[Eigen::Index(e)];
            value[edge_slot_[e]] += edge_off[Eigen::Index(e)];
        }
    }

    const SparseMatrix& matrix() const { return matrix_; }

private:
    std::int64_t slot(std::int64_t row, std::int64_t col) const {
        const int* first = matrix_.innerIndexPtr() + matrix_.outerIndexPtr()[col];
        const int* last = matrix_.innerIndexPtr() + matrix_.outerIndexPtr()[col + 1];
        const int* it = std::lower_bound(first, last, int(row));
        return it - matrix_.innerIndexPtr();
    }

    const std::vector<Edge>& edges_;
    SparseMatrix matrix_;
    std::vector<std::int64_t> diagonal_slot_, edge_slot_;
};

/// The reference grid step h of the header comment: the spacing itself when isotropic (so that
/// every weight is exactly 1), else the geometric mean.
double reference_step(const Eigen::Vector3d& s) {
    if (s.x() == s.y() && s.y() == s.z()) return s.x();
    return std::cbrt(s.x() * s.y() * s.z());
}

/// Axis along which edge (a, b) runs, from the pointels of its vertices.
int edge_axis(const DigitalSurface& surface, std::int32_t a, std::int32_t b) {
    for (int d = 0; d < 3; ++d)
        if (surface.vertex_pointels(a, d) != surface.vertex_pointels(b, d)) return d;
    throw Error("internal error: Ambrosio-Tortorelli found a degenerate surface edge");
}

void check_surface(const DigitalSurface& surface) {
    const std::int64_t m = surface.face_count();
    if (m == 0) throw Error("Ambrosio-Tortorelli: the surface has no face");
    if (surface.adjacent_face.rows() != m || surface.adjacent_face.cols() != 4 || surface.quads.cols() != 4 ||
        std::int64_t(surface.surfels.size()) != m || surface.vertex_pointels.rows() != surface.vertex_count())
        throw Error("Ambrosio-Tortorelli: inconsistent digital surface");
}

void compute_metric_weights(const DigitalSurface& surface, AtComplex& c) {
    const Eigen::Vector3d& s = surface.grid.spacing;
    const double h = reference_step(s);
    auto face_area = [&](std::int64_t f) {
        const int a = surface.surfels[std::size_t(f)].axis;
        return s[(a + 1) % 3] * s[(a + 2) % 3];
    };
    c.face_weights.resize(c.face_count);
    Eigen::VectorXd area_sum = Eigen::VectorXd::Zero(c.vertex_count);
    Eigen::VectorXd corner_count = Eigen::VectorXd::Zero(c.vertex_count);
    for (std::int64_t f = 0; f < c.face_count; ++f) {
        const double area = face_area(f);
        c.face_weights[f] = area / (h * h);
        for (int k = 0; k < 4; ++k) {
            area_sum[surface.quads(f, k)] += area;
            corner_count[surface.quads(f, k)] += 1;
        }
    }
    c.vertex_weights = (area_sum.array() / corner_count.array()) / (h * h);

    c.edge_u_weights.resize(c.edge_count());
    c.edge_v_weights.resize(c.edge_count());
    for (std::int64_t e = 0; e < c.edge_count(); ++e) {
        const auto [a, b] = c.edge_vertices[std::size_t(e)];
        const int along = edge_axis(surface, a, b);
        // Each face reaches across the edge along its third axis (neither its normal nor the edge).
        auto width = [&](std::int32_t f) { return s[3 - surface.surfels[std::size_t(f)].axis - along]; };
        const double length = s[along];
        const double dual_length = 0.5 * (width(c.edge_faces[std::size_t(e)][0]) + width(c.edge_faces[std::size_t(e)][1]));
        c.edge_u_weights[e] = length / dual_length;
        c.edge_v_weights[e] = dual_length / length;
    }
}

void check_field(const PointMatrix& g, std::int64_t face_count) {
    if (g.rows() != face_count)
        throw Error("Ambrosio-Tortorelli: the input field has " + std::to_string(g.rows()) + " vectors for " +
                    std::to_string(face_count) + " faces");
    for (std::int64_t f = 0; f < face_count; ++f)
        if (!g.row(f).allFinite() || g.row(f).squaredNorm() == 0)
            throw Error("Ambrosio-Tortorelli: input normal " + std::to_string(f) + " is zero or not finite");
}

/// (M v)_e
double edge_average(const Edge& e, const Eigen::VectorXd& v) { return 0.5 * (v[e[0]] + v[e[1]]); }

/// |(A u)_e|²
double squared_jump(const Edge& faces, const PointMatrix& u) { return (u.row(faces[0]) - u.row(faces[1])).squaredNorm(); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// Parameters and complex

void validate_at_parameters(const AmbrosioTortorelliParameters& p) {
    require_finite_positive(p.alpha, "alpha (--at-alpha)");
    require_finite_positive(p.lambda, "lambda (--at-lambda)");
    require_finite_positive(p.epsilon_start, "epsilon start (--at-eps)");
    require_finite_positive(p.epsilon_end, "epsilon end (--at-eps)");
    require_finite_positive(p.tolerance, "tolerance");
    if (p.epsilon_end > p.epsilon_start)
        throw Error("Ambrosio-Tortorelli: --at-eps goes from the larger epsilon to the smaller (got " +
                    number(p.epsilon_start) + ":" + number(p.epsilon_end) + ")");
    if (!(p.epsilon_ratio > 1) || !std::isfinite(p.epsilon_ratio))
        throw Error("Ambrosio-Tortorelli: --at-eps-ratio must be greater than 1 (got " + number(p.epsilon_ratio) + ")");
    if (p.max_rounds < 1) throw Error("Ambrosio-Tortorelli: at least one round per epsilon is needed");
}

std::vector<double> at_epsilon_levels(const AmbrosioTortorelliParameters& p) {
    validate_at_parameters(p);
    std::vector<double> levels;
    for (double eps = p.epsilon_start; eps > p.epsilon_end * (1 + 1e-9); eps /= p.epsilon_ratio) levels.push_back(eps);
    levels.push_back(p.epsilon_end);
    return levels;
}

AtComplex build_at_complex(const DigitalSurface& surface) {
    check_surface(surface);
    AtComplex c;
    c.face_count = surface.face_count();
    c.vertex_count = surface.vertex_count();
    c.edge_faces.reserve(std::size_t(2 * c.face_count));
    c.edge_vertices.reserve(std::size_t(2 * c.face_count));
    for (std::int64_t f = 0; f < c.face_count; ++f)
        for (int e = 0; e < 4; ++e) {
            const std::int32_t g = surface.adjacent_face(f, e);
            if (g < 0 || g >= c.face_count || g == f) throw Error("Ambrosio-Tortorelli: inconsistent face adjacency");
            if (g < f) continue;  // each edge once, from its lower-numbered face (the left one)
            c.edge_faces.push_back({std::int32_t(f), g});
            c.edge_vertices.push_back({surface.quads(f, e), surface.quads(f, (e + 1) % 4)});
        }
    compute_metric_weights(surface, c);
    return c;
}

AtOperators at_operators(const AtComplex& c) {
    std::vector<Eigen::Triplet<double>> a, d, m;
    for (std::int64_t e = 0; e < c.edge_count(); ++e) {
        const Edge& f = c.edge_faces[std::size_t(e)];
        const Edge& v = c.edge_vertices[std::size_t(e)];
        a.emplace_back(e, f[0], 1.0);
        a.emplace_back(e, f[1], -1.0);
        d.emplace_back(e, v[1], 1.0);
        d.emplace_back(e, v[0], -1.0);
        m.emplace_back(e, v[0], 0.5);
        m.emplace_back(e, v[1], 0.5);
    }
    AtOperators ops;
    ops.A.resize(c.edge_count(), c.face_count);
    ops.d0.resize(c.edge_count(), c.vertex_count);
    ops.M.resize(c.edge_count(), c.vertex_count);
    ops.A.setFromTriplets(a.begin(), a.end());
    ops.d0.setFromTriplets(d.begin(), d.end());
    ops.M.setFromTriplets(m.begin(), m.end());
    return ops;
}

AtEnergy at_energy(const AtComplex& c, const PointMatrix& g, const PointMatrix& u, const Eigen::VectorXd& v,
                   const AmbrosioTortorelliParameters& p, double epsilon) {
    AtEnergy energy;
    for (std::int64_t f = 0; f < c.face_count; ++f)
        energy.attachment += p.alpha * c.face_weights[f] * (u.row(f) - g.row(f)).squaredNorm();
    for (std::int64_t e = 0; e < c.edge_count(); ++e) {
        const Edge& ev = c.edge_vertices[std::size_t(e)];
        const double mv = edge_average(ev, v);
        const double dv = v[ev[1]] - v[ev[0]];
        energy.smoothness += c.edge_u_weights[e] * mv * mv * squared_jump(c.edge_faces[std::size_t(e)], u);
        energy.feature_gradient += p.lambda * epsilon * c.edge_v_weights[e] * dv * dv;
    }
    for (std::int64_t i = 0; i < c.vertex_count; ++i)
        energy.feature_length += p.lambda / (4 * epsilon) * c.vertex_weights[i] * (1 - v[i]) * (1 - v[i]);
    return energy;
}

// ---------------------------------------------------------------------------------------------
// Solver

/// The two fixed-pattern matrices, their solvers and the scratch vectors of the assembly.
struct AtSolver::Systems {
    explicit Systems(const AtComplex& c)
        : u_matrix(c.face_count, c.edge_faces), v_matrix(c.vertex_count, c.edge_vertices), u_solver("u"), v_solver("v") {}

    GraphMatrix u_matrix, v_matrix;
    at_detail::RefactoringSolver u_solver, v_solver;
    bool v_reusable = false;  ///< false after ε changed: the v-matrix changed too much to refine
    Eigen::MatrixXd u_solution;  ///< last u-solve, before normalization
    Eigen::VectorXd node, edge_diagonal, edge_off;

};

AtSolver::AtSolver(const DigitalSurface& surface, const PointMatrix& g, const AmbrosioTortorelliParameters& parameters)
    : parameters_(parameters), epsilon_(parameters.epsilon_start) {
    validate_at_parameters(parameters_);
    check_field(g, surface.face_count());
    complex_ = build_at_complex(surface);
    g_ = g.rowwise().normalized();
    u_ = g_;
    v_ = Eigen::VectorXd::Ones(complex_.vertex_count);
    systems_ = std::make_unique<Systems>(complex_);
}

AtSolver::~AtSolver() = default;

void AtSolver::set_epsilon(double epsilon) {
    require_finite_positive(epsilon, "epsilon");
    if (epsilon != epsilon_) systems_->v_reusable = false;
    epsilon_ = epsilon;
}

Eigen::MatrixXd AtSolver::u_rhs() const {
    return parameters_.alpha * (complex_.face_weights.asDiagonal() * g_);  // a W2 g
}

Eigen::VectorXd AtSolver::v_rhs() const {
    return parameters_.lambda / (4 * epsilon_) * complex_.vertex_weights;  // λ/(4ε) W0 1
}

double AtSolver::solve_u() {
    Systems& s = *systems_;
    const AtComplex& c = complex_;
    // (a W2 + Aᵀ diag(Wu (Mv)²) A): each edge adds w_e (δ_l − δ_r)(δ_l − δ_r)ᵀ.
    s.edge_diagonal.resize(c.edge_count());
    for (std::int64_t e = 0; e < c.edge_count(); ++e) {
        const double mv = edge_average(c.edge_vertices[std::size_t(e)], v_);
        s.edge_diagonal[e] = c.edge_u_weights[e] * mv * mv;
    }
    s.edge_off = -s.edge_diagonal;
    s.node = parameters_.alpha * c.face_weights;
    s.u_matrix.assemble(s.node, s.edge_diagonal, s.edge_off);

    // Refinement starts from the previous solution before normalization (closest to the new one).
    if (s.u_solution.rows() != u_.rows()) s.u_solution = u_;
    const double residual = s.u_solver.solve(s.u_matrix.matrix(), u_rhs(), s.u_solution, true, stats_);
    u_ = s.u_solution;
    max_u_residual_ = std::max(max_u_residual_, residual);
    return residual;
}

void AtSolver::normalize_u() {
    for (std::int64_t f = 0; f < complex_.face_count; ++f) {
        const double norm = u_.row(f).norm();
        if (norm > 0 && std::isfinite(norm))
            u_.row(f) /= norm;
        else
            u_.row(f) = g_.row(f);
    }
}

double AtSolver::solve_v() {
    Systems& s = *systems_;
    const AtComplex& c = complex_;
    const double gradient = parameters_.lambda * epsilon_;
    // λ/(4ε) W0 + λε d0ᵀ Wv d0 + Mᵀ diag(Wu |Au|²) M: edge (a,b) adds λε Wv (δ_b − δ_a)(δ_b − δ_a)ᵀ
    // and (Wu |Au|²/4) (δ_a + δ_b)(δ_a + δ_b)ᵀ.
    s.edge_diagonal.resize(c.edge_count());
    s.edge_off.resize(c.edge_count());
    for (std::int64_t e = 0; e < c.edge_count(); ++e) {
        const double jump = 0.25 * c.edge_u_weights[e] * squared_jump(c.edge_faces[std::size_t(e)], u_);
        const double diffusion = gradient * c.edge_v_weights[e];
        s.edge_diagonal[e] = diffusion + jump;
        s.edge_off[e] = -diffusion + jump;
    }
    s.node = parameters_.lambda / (4 * epsilon_) * c.vertex_weights;
    s.v_matrix.assemble(s.node, s.edge_diagonal, s.edge_off);

    Eigen::MatrixXd x = v_;
    const double residual = s.v_solver.solve(s.v_matrix.matrix(), v_rhs(), x, s.v_reusable, stats_);
    s.v_reusable = true;
    v_ = x.col(0);
    max_v_residual_ = std::max(max_v_residual_, residual);
    return residual;
}

double AtSolver::round() {
    solve_u();
    normalize_u();
    const Eigen::VectorXd previous = v_;
    solve_v();
    return (v_ - previous).lpNorm<Eigen::Infinity>();
}

AtEnergy AtSolver::energy() const { return at_energy(complex_, g_, u_, v_, parameters_, epsilon_); }

const SparseMatrix& AtSolver::u_matrix() const { return systems_->u_matrix.matrix(); }
const SparseMatrix& AtSolver::v_matrix() const { return systems_->v_matrix.matrix(); }

double AtSolver::u_factor_nonzeros() const { return systems_->u_solver.factor_nonzeros(); }
double AtSolver::v_factor_nonzeros() const { return systems_->v_solver.factor_nonzeros(); }

// ---------------------------------------------------------------------------------------------
// Schedule

namespace {

AtSolveStats difference(const AtSolveStats& after, const AtSolveStats& before) {
    AtSolveStats d;
    d.factorizations = after.factorizations - before.factorizations;
    d.refined_solves = after.refined_solves - before.refined_solves;
    d.refinement_iterations = after.refinement_iterations - before.refinement_iterations;
    return d;
}

}  // namespace

int AmbrosioTortorelliResult::total_rounds() const {
    int rounds = 0;
    for (const AtLevelReport& level : levels) rounds += level.rounds;
    return rounds;
}

AmbrosioTortorelliResult ambrosio_tortorelli_normals(const DigitalSurface& surface, const PointMatrix& g,
                                                     const AmbrosioTortorelliParameters& parameters) {
    const Clock::time_point start = Clock::now();
    const std::vector<double> levels = at_epsilon_levels(parameters);
    AtSolver solver(surface, g, parameters);
    AmbrosioTortorelliResult result;
    for (double epsilon : levels) {
        const Clock::time_point level_start = Clock::now();
        const AtSolveStats before = solver.solve_stats();
        solver.set_epsilon(epsilon);
        AtLevelReport level;
        level.epsilon = epsilon;
        while (level.rounds < parameters.max_rounds && !level.converged) {
            level.v_change = solver.round();
            ++level.rounds;
            level.converged = level.v_change < parameters.tolerance;
        }
        level.energy = solver.energy().total();
        level.solves = difference(solver.solve_stats(), before);
        level.seconds = seconds_since(level_start);
        result.levels.push_back(level);
    }
    result.normals = solver.u();
    result.features = solver.v();
    result.max_u_residual = solver.max_u_residual();
    result.max_v_residual = solver.max_v_residual();
    result.u_factor_nonzeros = solver.u_factor_nonzeros();
    result.v_factor_nonzeros = solver.v_factor_nonzeros();
    result.solves = solver.solve_stats();
    result.seconds = seconds_since(start);
    return result;
}

}  // namespace dsreg
