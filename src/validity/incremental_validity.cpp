// dsreg — incremental validity checks (incremental_validity.hpp).
#include "incremental_validity.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "triangle_predicates.hpp"

#include "dsreg/evaluation.hpp"

namespace dsreg::validity_internal {

namespace {

using Clock = std::chrono::steady_clock;

struct Box {
    Eigen::Array3d low, high;
};

Box triangle_box(const PointMatrix& vertices, const FaceMatrix& triangles, Eigen::Index t) {
    Box box{vertices.row(triangles(t, 0)).transpose().array(), vertices.row(triangles(t, 0)).transpose().array()};
    for (int k = 1; k < 3; ++k) {
        box.low = box.low.min(vertices.row(triangles(t, k)).transpose().array());
        box.high = box.high.max(vertices.row(triangles(t, k)).transpose().array());
    }
    return box;
}

void sort_unique(std::vector<std::int64_t>& values) {
    std::sort(values.begin(), values.end());
    values.erase(std::unique(values.begin(), values.end()), values.end());
}

/// A box in single precision, rounded outwards: it contains the box it was made from, so the
/// candidate pairs it gives are a superset of the exact boxes' (the pairs are decided by the
/// exact predicate) in half the memory.
struct CoarseBox {
    Eigen::Array3f low, high;

    explicit CoarseBox(const Box& box) {
        for (int a = 0; a < 3; ++a) {
            low[a] = float(box.low[a]);
            if (double(low[a]) > box.low[a]) low[a] = std::nextafter(low[a], -std::numeric_limits<float>::infinity());
            high[a] = float(box.high[a]);
            if (double(high[a]) < box.high[a]) high[a] = std::nextafter(high[a], std::numeric_limits<float>::infinity());
        }
    }
    bool overlaps(const CoarseBox& o) const { return (low <= o.high).all() && (o.low <= high).all(); }
};

}  // namespace

/// Triangles bucketed by the cubic cells their bounding boxes overlap, kept up to date as they
/// move: building it costs a hash-map entry per triangle and cell, so it is built once, with
/// cells of twice the mean box extent of the mesh as checked first, and only the triangles that
/// moved change cells afterwards.
class IncrementalValidity::BoxGrid {
public:
    BoxGrid(const PointMatrix& vertices, const FaceMatrix& triangles) {
        boxes_.reserve(std::size_t(triangles.rows()));
        double extent = 0;
        for (Eigen::Index t = 0; t < triangles.rows(); ++t) {
            boxes_.emplace_back(triangle_box(vertices, triangles, t));
            extent += (boxes_.back().high - boxes_.back().low).maxCoeff();
        }
        inverse_cell_ = 1 / std::max(2 * extent / double(std::max<Eigen::Index>(triangles.rows(), 1)), 1e-12);
        for (std::size_t t = 0; t < boxes_.size(); ++t) for_cells(boxes_[t], [&](std::int64_t key) { cells_[key].push_back(std::int32_t(t)); });
    }

    /// Triangle t now has its corners at `vertices`.
    void move(const PointMatrix& vertices, const FaceMatrix& triangles, std::int64_t t) {
        for_cells(boxes_[std::size_t(t)], [&](std::int64_t key) {
            std::vector<std::int32_t>& cell = cells_[key];
            const auto it = std::find(cell.begin(), cell.end(), std::int32_t(t));
            *it = cell.back();
            cell.pop_back();
        });
        boxes_[std::size_t(t)] = CoarseBox(triangle_box(vertices, triangles, t));
        for_cells(boxes_[std::size_t(t)], [&](std::int64_t key) { cells_[key].push_back(std::int32_t(t)); });
    }

    /// Appends the triangles other than t whose boxes meet the box of triangle t, each once
    /// (sorted). Safe to call from several threads.
    void overlapping(std::int64_t t, std::vector<std::int64_t>& out) const {
        const std::size_t first = out.size();
        const CoarseBox& box = boxes_[std::size_t(t)];
        for_cells(box, [&](std::int64_t key) {
            const auto it = cells_.find(key);
            if (it == cells_.end()) return;
            for (const std::int32_t other : it->second)
                if (other != t && boxes_[std::size_t(other)].overlaps(box)) out.push_back(other);
        });
        std::sort(out.begin() + std::ptrdiff_t(first), out.end());
        out.erase(std::unique(out.begin() + std::ptrdiff_t(first), out.end()), out.end());
    }

private:
    template <class Visit>
    void for_cells(const CoarseBox& box, Visit visit) const {
        const Eigen::Array3i low = (box.low.cast<double>() * inverse_cell_).floor().cast<int>(),
                             high = (box.high.cast<double>() * inverse_cell_).floor().cast<int>();
        for (int z = low.z(); z <= high.z(); ++z)
            for (int y = low.y(); y <= high.y(); ++y)
                for (int x = low.x(); x <= high.x(); ++x)
                    visit((std::int64_t(x) & 0x1fffff) | ((std::int64_t(y) & 0x1fffff) << 21) | ((std::int64_t(z) & 0x1fffff) << 42));
    }

    std::vector<CoarseBox> boxes_;
    double inverse_cell_ = 1;  ///< 1 / the side of a cell
    std::unordered_map<std::int64_t, std::vector<std::int32_t>> cells_;
};

IncrementalValidity::IncrementalValidity(const PointMatrix& vertices, const FaceMatrix& quads, const PointMatrix& field)
    : quads_(quads) {
    const auto started = Clock::now();
    corners_ = vertex_corners(quads, vertices.rows());
    triangles_ = mesh_triangles(vertices, quads);
    const TriangleSelfIntersections found = triangle_self_intersections(vertices, triangles_);
    pairs_ = found.pairs;
    degenerate_.assign(std::size_t(triangles_.rows()), 0);
    for (const std::int64_t t : found.degenerate) degenerate_[std::size_t(t)] = 1;
    folded_.assign(std::size_t(quads.rows()), 0);
    for (const std::int32_t q : faces_folded_against_field(vertices, quads, field)) folded_[std::size_t(q)] = 1;
    seconds_ = std::chrono::duration<double>(Clock::now() - started).count();
}

IncrementalValidity::~IncrementalValidity() = default;

void IncrementalValidity::update(const PointMatrix& vertices, const std::vector<std::int32_t>& moved,
                                 const std::vector<std::int32_t>& refield, const PointMatrix& field) {
    const auto started = Clock::now();
    std::vector<std::int32_t> quads = refield;
    for (const std::int32_t v : moved) corners_.for_each_face(v, [&](std::int32_t q) { quads.push_back(q); });
    std::sort(quads.begin(), quads.end());
    quads.erase(std::unique(quads.begin(), quads.end()), quads.end());
    if (!quads.empty()) retest(vertices, quads, field);
    seconds_ += std::chrono::duration<double>(Clock::now() - started).count();
}

void IncrementalValidity::retest(const PointMatrix& vertices, const std::vector<std::int32_t>& quads_to_test,
                                 const PointMatrix& field) {
    // The split and the fold test of the quads concerned.
    FaceMatrix subset(Eigen::Index(quads_to_test.size()), 4);
    PointMatrix subset_field(subset.rows(), 3);
    for (std::size_t k = 0; k < quads_to_test.size(); ++k) {
        subset.row(Eigen::Index(k)) = quads_.row(quads_to_test[k]);
        subset_field.row(Eigen::Index(k)) = field.row(quads_to_test[k]);
    }
    const FaceMatrix split = mesh_triangles(vertices, subset);
    std::vector<std::int64_t> changed;
    for (std::size_t k = 0; k < quads_to_test.size(); ++k) {
        const std::int64_t q = quads_to_test[k];
        triangles_.row(2 * q) = split.row(2 * Eigen::Index(k));
        triangles_.row(2 * q + 1) = split.row(2 * Eigen::Index(k) + 1);
        changed.push_back(2 * q);
        changed.push_back(2 * q + 1);
        folded_[std::size_t(q)] = 0;
    }
    for (const std::int32_t k : faces_folded_against_field(vertices, subset, subset_field)) folded_[std::size_t(quads_to_test[std::size_t(k)])] = 1;

    // The pairs of a changed triangle and a triangle whose box meets its box, each decided once
    // by the rule of triangle_self_intersections (degenerate triangles take part in no pair).
    if (!grid_) grid_ = std::make_unique<BoxGrid>(vertices, triangles_);
    for (const std::int64_t t : changed) grid_->move(vertices, triangles_, t);
    std::vector<char> is_changed(std::size_t(triangles_.rows()), 0);
    for (const std::int64_t t : changed) is_changed[std::size_t(t)] = 1;
    const std::int64_t count = std::int64_t(changed.size());
#pragma omp parallel for schedule(static) if (count > 4096)
    for (std::int64_t k = 0; k < count; ++k)
        degenerate_[std::size_t(changed[std::size_t(k)])] = triangle_is_degenerate(vertices, triangles_, changed[std::size_t(k)]);
    std::vector<std::pair<std::int64_t, std::int64_t>> found;
#pragma omp parallel if (count > 1024)
    {
        std::vector<std::pair<std::int64_t, std::int64_t>> mine;
        std::vector<std::int64_t> near;
#pragma omp for schedule(dynamic, 256) nowait
        for (std::int64_t k = 0; k < count; ++k) {
            const std::int64_t t = changed[std::size_t(k)];
            if (degenerate_[std::size_t(t)]) continue;
            near.clear();
            grid_->overlapping(t, near);
            for (const std::int64_t other : near) {
                if (degenerate_[std::size_t(other)] || (is_changed[std::size_t(other)] && other < t)) continue;
                if (triangles_meet_beyond_shared_indices(vertices, triangles_, t, other))
                    mine.emplace_back(std::min(t, other), std::max(t, other));
            }
        }
#pragma omp critical
        found.insert(found.end(), mine.begin(), mine.end());
    }

    std::vector<std::pair<std::int64_t, std::int64_t>> kept;
    for (const auto& pair : pairs_)
        if (!is_changed[std::size_t(pair.first)] && !is_changed[std::size_t(pair.second)]) kept.push_back(pair);
    kept.insert(kept.end(), found.begin(), found.end());
    std::sort(kept.begin(), kept.end());
    pairs_.swap(kept);
}

MeshValidity IncrementalValidity::validity() const {
    MeshValidity v;
    v.faces = quads_.rows();
    v.triangles = triangles_.rows();
    v.intersecting_pairs = std::int64_t(pairs_.size());
    std::vector<std::int64_t> involved;
    for (const auto& [a, b] : pairs_) {
        involved.push_back(a / 2);
        involved.push_back(b / 2);
    }
    for (std::size_t t = 0; t < degenerate_.size(); ++t)
        if (degenerate_[t]) {
            ++v.degenerate_triangles;
            involved.push_back(std::int64_t(t / 2));
        }
    sort_unique(involved);
    v.intersecting_faces.assign(involved.begin(), involved.end());
    for (std::size_t q = 0; q < folded_.size(); ++q)
        if (folded_[q]) v.folded.push_back(std::int32_t(q));
    v.folded_faces = std::int64_t(v.folded.size());
    v.seconds = seconds_;
    return v;
}

}  // namespace dsreg::validity_internal
