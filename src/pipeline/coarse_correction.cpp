// dsreg pipeline — the two-level (coarse-grid) correction of the streaming mode
// (include/dsreg/block_pipeline.hpp).
#include <Eigen/SparseCholesky>
#include <algorithm>

#include "dsreg/block_pipeline.hpp"
#include "dsreg/error.hpp"

namespace dsreg {

namespace {

/// A column of P_scalar whose LDLᵀ pivot (its squared distance to the span of the columns
/// eliminated before it, in PᵀP's inner product) is below this fraction of its squared norm lies,
/// to within an angle of 3e-5 rad, in that span: the node is dropped. Exact dependencies (e.g. a
/// flat patch of surface inside a cell, where a Q1 function can vanish at every vertex) give
/// pivots at rounding level.
constexpr double kDependentPivot = 1e-9;

std::int64_t local_index(const std::vector<std::int64_t>& sorted, std::int64_t value) {
    return std::lower_bound(sorted.begin(), sorted.end(), value) - sorted.begin();
}

bool contains(const std::vector<std::int64_t>& sorted, std::int64_t value) {
    return std::binary_search(sorted.begin(), sorted.end(), value);
}

/// The principal submatrix of `m` on the indices with `kept` (renumbered in order).
Eigen::SparseMatrix<double> kept_part(const Eigen::SparseMatrix<double>& m, const std::vector<std::int64_t>& new_index,
                                      std::int64_t size) {
    std::vector<Eigen::Triplet<double>> entries;
    for (Eigen::Index c = 0; c < m.outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(m, c); it; ++it) {
            const std::int64_t row = new_index[std::size_t(it.row())], column = new_index[std::size_t(c)];
            if (row >= 0 && column >= 0) entries.emplace_back(Eigen::Index(row), Eigen::Index(column), it.value());
        }
    Eigen::SparseMatrix<double> part(size, size);
    part.setFromTriplets(entries.begin(), entries.end());
    return part;
}

/// Renumbers the indices with kept[i] consecutively (−1 for the others); returns their count.
std::int64_t renumber(const std::vector<char>& kept, std::vector<std::int64_t>& new_index) {
    new_index.assign(kept.size(), -1);
    std::int64_t count = 0;
    for (std::size_t i = 0; i < kept.size(); ++i)
        if (kept[i]) new_index[i] = count++;
    return count;
}

/// The pivots of an LDLᵀ of `gram` (+ shift·I), by column of `gram`; false if it broke down.
bool ldlt_pivots(const Eigen::SparseMatrix<double>& gram, double shift, Eigen::VectorXd& pivots) {
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
    ldlt.setShift(shift);
    ldlt.compute(gram);
    if (ldlt.info() != Eigen::Success) return false;
    // L D Lᵀ = Q (G + shift·I) Qᵀ: column i of G is pivot Q.indices()[i].
    const auto& order = ldlt.permutationP().indices();
    pivots.resize(gram.rows());
    for (Eigen::Index i = 0; i < gram.rows(); ++i) pivots[i] = ldlt.vectorD()[order[i]];
    return true;
}

/// The nodes whose columns of P_scalar are independent (numerically: every LDLᵀ pivot of their
/// Gram matrix, scaled to a unit diagonal, at least kDependentPivot: the squared sine of the angle
/// between a column and the span of those eliminated before it). A shifted factorization finds
/// the dependent columns (an exact dependency gives a zero pivot, where the unshifted one stops;
/// the shift only raises each pivot, by at most shift·(1 + ‖combination‖²)); the unshifted
/// factorization of what is kept then proves the rank.
std::vector<char> independent_nodes(const Eigen::SparseMatrix<double>& gram) {
    const std::int64_t n = gram.rows();
    const Eigen::VectorXd scale = gram.diagonal().cwiseSqrt().cwiseInverse();
    const Eigen::SparseMatrix<double> unit = scale.asDiagonal() * gram * scale.asDiagonal();
    const double shift = 1e-3 * kDependentPivot;
    std::vector<char> kept(std::size_t(n), 1);
    std::vector<std::int64_t> new_index;
    for (int round = 0; round < 16; ++round) {
        const std::int64_t count = renumber(kept, new_index);
        const Eigen::SparseMatrix<double> part = kept_part(unit, new_index, count);
        Eigen::VectorXd pivots;
        if (ldlt_pivots(part, 0.0, pivots) && pivots.minCoeff() >= kDependentPivot) return kept;
        if (!ldlt_pivots(part, shift, pivots)) break;
        for (std::int64_t i = 0; i < n; ++i)
            if (kept[std::size_t(i)] && pivots[new_index[std::size_t(i)]] < kDependentPivot) kept[std::size_t(i)] = 0;
    }
    throw Error("coarse correction: could not find independent coarse nodes (internal error)");
}

}  // namespace

CoarseLattice::Stencil CoarseLattice::stencil(std::int64_t vertex_key) const {
    // Pointel q on axis a lies between nodes n = q / s and n + 1 (s = spacing), at t = (q mod s) / s.
    const Index3 q = pointel_of_vertex_key(dims, vertex_key);
    Index3 lower{0, 0, 0}, rest{0, 0, 0}, nodes_along{0, 0, 0};
    for (int a = 0; a < 3; ++a) {
        lower[a] = q[a] / spacing;
        rest[a] = q[a] % spacing;
        nodes_along[a] = dims[a] / spacing + 2;
    }
    Stencil s;
    for (int corner = 0; corner < 8; ++corner) {
        double weight = 1;
        std::int64_t node = 0;
        for (int a = 2; a >= 0; --a) {
            const bool upper = (corner >> a) & 1;
            if (upper && rest[a] == 0) weight = 0;  // on the lower node's plane: no weight above
            weight *= double(upper ? rest[a] : spacing - rest[a]) / double(spacing);
            node = node * nodes_along[a] + lower[a] + upper;
        }
        if (weight == 0) continue;
        s.nodes[std::size_t(s.count)] = node;
        s.weights[std::size_t(s.count)] = weight;
        ++s.count;
    }
    return s;
}

CoarseShare coarse_share(const BlockStages& block, const CoarseLattice& lattice, const Eigen::VectorXd& x,
                         const Eigen::VectorXd& owned_residual, const PointMatrix& directions) {
    const SurfacePatch& patch = block.patch;
    const std::int64_t n = patch.vertex_count();
    std::vector<CoarseLattice::Stencil> stencils(static_cast<std::size_t>(n));
    CoarseShare share;
    const bool along = directions.rows() > 0;
    const int k3 = share.unknowns_per_node = along ? 1 : 3;
    for (std::int64_t i = 0; i < n; ++i) {
        stencils[std::size_t(i)] = lattice.stencil(patch.vertex_keys[std::size_t(i)]);
        const auto& s = stencils[std::size_t(i)];
        share.nodes.insert(share.nodes.end(), s.nodes.begin(), s.nodes.begin() + s.count);
    }
    std::sort(share.nodes.begin(), share.nodes.end());
    share.nodes.erase(std::unique(share.nodes.begin(), share.nodes.end()), share.nodes.end());
    const std::int64_t m = std::int64_t(share.nodes.size());
    // P on the patch's vertices, and its owned rows (the others zero).
    std::vector<Eigen::Triplet<double>> all, owned, owned_scalar;
    for (std::int64_t i = 0; i < n; ++i) {
        const auto& s = stencils[std::size_t(i)];
        const bool is_owned = patch.vertex_owned[std::size_t(i)];
        for (int k = 0; k < s.count; ++k) {
            const std::int64_t node = local_index(share.nodes, s.nodes[std::size_t(k)]);
            const double w = s.weights[std::size_t(k)];
            for (int d = 0; d < 3; ++d) {
                const Eigen::Index column = along ? Eigen::Index(node) : Eigen::Index(3 * node + d);
                const double value = along ? w * directions(i, d) : w;
                all.emplace_back(Eigen::Index(3 * i + d), column, value);
                if (is_owned) owned.emplace_back(Eigen::Index(3 * i + d), column, value);
            }
            if (is_owned) owned_scalar.emplace_back(Eigen::Index(i), Eigen::Index(node), w);
        }
    }
    Eigen::SparseMatrix<double> P(3 * n, k3 * m), P_owned(3 * n, k3 * m), P_scalar(n, m);
    P.setFromTriplets(all.begin(), all.end());
    P_owned.setFromTriplets(owned.begin(), owned.end());
    P_scalar.setFromTriplets(owned_scalar.begin(), owned_scalar.end());
    const Eigen::SparseMatrix<double> RP = block.system.matrix * P;
    share.galerkin = Eigen::SparseMatrix<double>(P_owned.transpose()) * RP;
    share.gram = Eigen::SparseMatrix<double>(P_scalar.transpose()) * P_scalar;
    share.residual = -(P_owned.transpose() * owned_residual);
    // ½ xᵀRx − bᵀx summed row by row over the owned vertices: ½ x_i·(r_i + b_i) − b_i·x_i.
    for (std::int64_t i = 0; i < n; ++i)
        if (patch.vertex_owned[std::size_t(i)]) {
            const Eigen::Vector3d xi = x.segment<3>(3 * i), bi = block.system.rhs.segment<3>(3 * i);
            share.energy += 0.5 * xi.dot(owned_residual.segment<3>(3 * i)) - 0.5 * bi.dot(xi);
        }
    return share;
}

Eigen::Vector3d CoarseSolution::displacement(const CoarseLattice& lattice, std::int64_t vertex_key,
                                             const Eigen::Vector3d& direction) const {
    const CoarseLattice::Stencil s = lattice.stencil(vertex_key);
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    for (int k = 0; k < s.count; ++k) {
        const std::int64_t node = s.nodes[std::size_t(k)];
        if (!contains(nodes, node)) throw Error("coarse correction: a vertex's node is not in the coarse system (internal error)");
        const std::int64_t i = local_index(nodes, node);
        d += s.weights[std::size_t(k)] *
             (unknowns_per_node == 3 ? Eigen::Vector3d(correction.segment<3>(3 * i)) : Eigen::Vector3d(correction[i] * direction));
    }
    return d;
}

void CoarseSystem::merge(std::vector<Entry>& entries) {
    std::sort(entries.begin(), entries.end(),
              [](const Entry& a, const Entry& b) { return a.row != b.row ? a.row < b.row : a.column < b.column; });
    std::size_t out = 0;
    for (std::size_t i = 0; i < entries.size(); ++i) {
        if (out > 0 && entries[out - 1].row == entries[i].row && entries[out - 1].column == entries[i].column)
            entries[out - 1].value += entries[i].value;
        else
            entries[out++] = entries[i];
    }
    entries.resize(out);
}

void CoarseSystem::add_matrix(std::vector<Entry>& entries, const Eigen::SparseMatrix<double>& m,
                              const std::vector<std::int64_t>& nodes, int per_node) {
    const auto global = [&](Eigen::Index local) { return per_node * nodes[std::size_t(local / per_node)] + local % per_node; };
    for (Eigen::Index c = 0; c < m.outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(m, c); it; ++it)
            entries.push_back({global(it.row()), global(c), it.value()});
}

void CoarseSystem::add(const CoarseShare& share) {
    const int k = unknowns_per_node_ = share.unknowns_per_node;
    add_matrix(galerkin_, share.galerkin, share.nodes, k);
    add_matrix(gram_, share.gram, share.nodes, 1);
    for (Eigen::Index i = 0; i < share.residual.size(); ++i)
        residual_.push_back({k * share.nodes[std::size_t(i / k)] + i % k, 0, share.residual[i]});
    energy_ += share.energy;
    if (galerkin_.size() > 2 * merged_size_ + (std::size_t(1) << 20)) {  // neighbouring blocks share nodes
        merge(galerkin_), merge(gram_), merge(residual_);
        merged_size_ = galerkin_.size();
    }
}

CoarseSolution CoarseSystem::solve() {
    merge(galerkin_), merge(gram_), merge(residual_);
    CoarseSolution solution;
    const int k = solution.unknowns_per_node = unknowns_per_node_;
    solution.energy_before = energy_;
    for (const Entry& e : gram_)
        if (solution.nodes.empty() || solution.nodes.back() != e.row) solution.nodes.push_back(e.row);  // rows sorted
    const std::int64_t n = std::int64_t(solution.nodes.size());
    solution.correction = Eigen::VectorXd::Zero(k * n);
    if (n == 0) return solution;
    const auto to_matrix = [&](const std::vector<Entry>& entries, int per_node) {
        const auto local = [&](std::int64_t global) {
            if (!contains(solution.nodes, global / per_node))
                throw Error("coarse correction: an entry off the touched nodes (internal error)");
            return per_node * local_index(solution.nodes, global / per_node) + global % per_node;
        };
        std::vector<Eigen::Triplet<double>> triplets;
        triplets.reserve(entries.size());
        for (const Entry& e : entries) triplets.emplace_back(Eigen::Index(local(e.row)), Eigen::Index(local(e.column)), e.value);
        Eigen::SparseMatrix<double> m(per_node * n, per_node * n);
        m.setFromTriplets(triplets.begin(), triplets.end());
        return m;
    };
    const std::vector<char> kept = independent_nodes(to_matrix(gram_, 1));
    std::vector<char> kept_unknowns(std::size_t(k * n));
    for (std::size_t i = 0; i < kept_unknowns.size(); ++i) kept_unknowns[i] = kept[i / std::size_t(k)];
    std::vector<std::int64_t> new_index;
    const std::int64_t unknowns = renumber(kept_unknowns, new_index);
    solution.dropped_nodes = n - unknowns / k;
    const Eigen::SparseMatrix<double> C = kept_part(to_matrix(galerkin_, k), new_index, unknowns);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(unknowns);
    for (const Entry& e : residual_) {
        const std::int64_t i = new_index[std::size_t(k * local_index(solution.nodes, e.row / k) + e.row % k)];
        if (i >= 0) g[i] = e.value;
    }
    SolverOptions direct;
    direct.kind = SolverKind::Cholmod;
    Eigen::VectorXd e;
    solve_spd(C, g, e, direct);
    for (std::size_t i = 0; i < new_index.size(); ++i)
        if (new_index[i] >= 0) solution.correction[Eigen::Index(i)] = e[new_index[i]];
    solution.energy_decrease = 0.5 * g.dot(e);  // E(x̃ + Pe) = E(x̃) − gᵀe + ½ eᵀCe, Ce = g
    return solution;
}

}  // namespace dsreg
