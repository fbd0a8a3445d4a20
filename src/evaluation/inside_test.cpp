// dsreg — which voxel centres lie inside a closed triangle mesh: parity of ray crossings along
// +x, one sorted list of crossings per voxel row.
#include <algorithm>
#include <cmath>
#include <string>

#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"

namespace dsreg {
namespace {

/// A point of the y-z plane (the projection along x).
struct Point2 {
    double y, z;
};

bool lexicographically_less(const Point2& a, const Point2& b) { return a.y < b.y || (a.y == b.y && a.z < b.z); }

/// Side of the ray point x with respect to the directed edge p→q, in the y-z plane.
struct EdgeSide {
    double value;  ///< cross(q − p, x − p), unperturbed (used for barycentric weights)
    int sign;      ///< sign after the symbolic perturbation x → x + (ε, ε²); 0 only if p = q
};

/// The edge function is evaluated with the endpoints in lexicographic order and negated for the
/// other direction, so the two triangles sharing an edge get bit-identical values. Where it is
/// exactly zero (the ray meets the edge line), the ray is moved to x + (ε, ε²) with ε → 0:
/// cross(d, (ε, ε²)) = d.y·ε² − d.z·ε, whose sign is that of −d.z, or of d.y when d.z = 0.
/// A generic ray then crosses every edge and vertex consistently in all incident triangles.
EdgeSide edge_side(Point2 p, Point2 q, const Point2& x) {
    double orientation = 1.0;
    if (lexicographically_less(q, p)) {
        std::swap(p, q);
        orientation = -1.0;
    }
    const double dy = q.y - p.y, dz = q.z - p.z;
    const double value = dy * (x.z - p.z) - dz * (x.y - p.y);
    int sign;
    if (value != 0.0) sign = value > 0 ? 1 : -1;
    else if (dz != 0.0) sign = dz > 0 ? -1 : 1;
    else sign = dy > 0 ? 1 : (dy < 0 ? -1 : 0);
    return EdgeSide{orientation * value, int(orientation) * sign};
}

/// If the ray through `ray` (a point of the y-z plane) along x crosses triangle t, stores the x
/// of the crossing and returns true.
bool ray_crossing(const PointMatrix& v, const FaceMatrix& triangles, Eigen::Index t, const Point2& ray, double& x) {
    const std::int32_t a = triangles(t, 0), b = triangles(t, 1), c = triangles(t, 2);
    const Point2 pa{v(a, 1), v(a, 2)}, pb{v(b, 1), v(b, 2)}, pc{v(c, 1), v(c, 2)};
    const EdgeSide ab = edge_side(pa, pb, ray), bc = edge_side(pb, pc, ray), ca = edge_side(pc, pa, ray);
    if (ab.sign == 0 || ab.sign != bc.sign || bc.sign != ca.sign) return false;
    const double twice_area = ab.value + bc.value + ca.value;
    if (twice_area == 0.0) return false;
    // Barycentric weights: the edge function of the opposite edge.
    x = (bc.value * v(a, 0) + ca.value * v(b, 0) + ab.value * v(c, 0)) / twice_area;
    return true;
}

/// Range of row indices whose coordinate origin + spacing·index lies in [low, high], widened by
/// a millionth of a row on each side against the rounding of the division (far more than its
/// relative error of 1e-16 on indices below 2^31; the exact test decides). A triangle of about a
/// voxel then lists 1–2 rows per axis instead of 3–4 with a whole row on each side.
std::pair<std::int64_t, std::int64_t> row_range(double low, double high, double origin, double spacing,
                                                std::int64_t count) {
    constexpr double kSlack = 1e-6;
    const double first = std::ceil((low - origin) / spacing - kSlack);
    const double last = std::floor((high - origin) / spacing + kSlack);
    const std::int64_t lo = std::int64_t(std::clamp(first, 0.0, double(count)));
    const std::int64_t hi = std::int64_t(std::clamp(last, -1.0, double(count - 1)));
    return {lo, hi};
}

void check_triangle(const PointMatrix& vertices, const FaceMatrix& triangles, Eigen::Index t, const char* caller) {
    for (int k = 0; k < 3; ++k)
        if (triangles(t, k) < 0 || triangles(t, k) >= vertices.rows())
            throw Error(std::string(caller) + ": triangle " + std::to_string(t) + " has a vertex index out of range");
}

void check_triangles(const PointMatrix& vertices, const FaceMatrix& triangles, const char* caller) {
    if (triangles.rows() > 0 && triangles.cols() != 3) throw Error(std::string(caller) + ": the faces must be triangles");
    for (Eigen::Index t = 0; t < triangles.rows(); ++t) check_triangle(vertices, triangles, t, caller);
}

/// Sets bits [from, to) of `words` to 1.
void set_bits(std::uint64_t* words, std::int64_t from, std::int64_t to) {
    while (from < to) {
        const std::int64_t word = from / 64, bit = from % 64, count = std::min<std::int64_t>(64 - bit, to - from);
        const std::uint64_t ones = count == 64 ? ~std::uint64_t(0) : ((std::uint64_t(1) << count) - 1) << bit;
        words[word] |= ones;
        from += count;
    }
}

/// Classifies the voxel centres of row (j, k) into `row_words` (nx bits, 1 inside, the words
/// cleared first) against the triangles [first, last) (those whose y-z box covers the row, in
/// any order: the crossings are sorted). `crossings` is work space.
void classify_row(const PointMatrix& vertices, const FaceMatrix& triangles, const VoxelGrid& grid, std::int64_t j,
                  std::int64_t k, const std::int32_t* first, const std::int32_t* last, std::vector<double>& crossings,
                  std::uint64_t* row_words) {
    const std::int64_t nx = grid.dims[0];
    std::fill(row_words, row_words + (nx + 63) / 64, std::uint64_t(0));
    const Eigen::Vector3d start = grid.voxel_center(0, j, k);
    const Point2 ray{start.y(), start.z()};
    crossings.clear();
    for (const std::int32_t* t = first; t != last; ++t) {
        double x;
        if (ray_crossing(vertices, triangles, *t, ray, x)) crossings.push_back(x);
    }
    if (crossings.empty()) return;
    std::sort(crossings.begin(), crossings.end());
    // Voxel i is inside iff an odd number of crossings lie beyond x_i: the voxels between
    // crossings p − 1 and p (x_{p−1} ≤ x_i < x_p) are inside iff m − p is odd.
    const auto voxel_x = [&](std::int64_t i) { return start.x() + grid.spacing.x() * double(i); };
    const auto first_at_or_beyond = [&](double c) {  // the first i with x_i ≥ c
        std::int64_t i = std::int64_t(std::clamp(std::ceil((c - start.x()) / grid.spacing.x()), 0.0, double(nx)));
        while (i > 0 && voxel_x(i - 1) >= c) --i;
        while (i < nx && voxel_x(i) < c) ++i;
        return i;
    };
    const std::size_t m = crossings.size();
    std::int64_t from = 0;
    for (std::size_t p = 0; p <= m; ++p) {
        const std::int64_t to = p < m ? first_at_or_beyond(crossings[p]) : nx;
        if ((m - p) % 2 == 1 && to > from) set_bits(row_words, from, to);
        from = std::max(from, to);
    }
}

}  // namespace

VoxelCentresInside::VoxelCentresInside(const PointMatrix& vertices, const FaceMatrix& triangles, const VoxelGrid& grid)
    : grid_(grid), row_triangles_(std::size_t(grid.dims[1] * grid.dims[2])),
      triangle_rows_(std::size_t(triangles.rows())), words_per_row_((grid.dims[0] + 63) / 64),
      bits_(std::size_t(words_per_row_ * grid.dims[1] * grid.dims[2]), 0) {
    check_triangles(vertices, triangles, "voxel_centres_inside");
    for (Eigen::Index t = 0; t < triangles.rows(); ++t) {
        triangle_rows_[std::size_t(t)] = rows_of(vertices, triangles, t);
        for_each_row(triangle_rows_[std::size_t(t)], [&](std::int64_t row) { row_triangles_[std::size_t(row)].push_back(std::int32_t(t)); });
    }
    std::vector<std::int64_t> all_rows;
    all_rows.reserve(row_triangles_.size());
    for (std::size_t row = 0; row < row_triangles_.size(); ++row)
        if (!row_triangles_[row].empty()) all_rows.push_back(std::int64_t(row));
    classify(vertices, triangles, all_rows);
}

std::vector<std::int64_t> VoxelCentresInside::update(const PointMatrix& vertices, const FaceMatrix& triangles,
                                                     const std::vector<std::int32_t>& changed) {
    if (std::size_t(triangles.rows()) != triangle_rows_.size() || (triangles.rows() > 0 && triangles.cols() != 3))
        throw Error("VoxelCentresInside::update: " + std::to_string(triangles.rows()) + " faces of " +
                    std::to_string(triangles.cols()) + " vertices, " + std::to_string(triangle_rows_.size()) +
                    " triangles expected");
    for (const std::int32_t t : changed) {
        if (t < 0 || t >= triangles.rows())
            throw Error("VoxelCentresInside::update: triangle " + std::to_string(t) + " out of range");
        check_triangle(vertices, triangles, t, "VoxelCentresInside::update");
    }
    // The changed triangles leave the rows they were listed in (one pass over each such row),
    // then join the rows of their new boxes.
    std::vector<char> is_changed(triangle_rows_.size(), 0), flagged(row_triangles_.size(), 0);
    std::vector<std::int64_t> rows;
    const auto flag = [&](std::int64_t row) {
        if (!flagged[std::size_t(row)]) flagged[std::size_t(row)] = 1, rows.push_back(row);
    };
    for (const std::int32_t t : changed) {
        is_changed[std::size_t(t)] = 1;
        for_each_row(triangle_rows_[std::size_t(t)], flag);
    }
    for (const std::int64_t row : rows) {
        std::vector<std::int32_t>& listed = row_triangles_[std::size_t(row)];
        listed.erase(std::remove_if(listed.begin(), listed.end(), [&](std::int32_t t) { return is_changed[std::size_t(t)] != 0; }),
                     listed.end());
    }
    for (const std::int32_t t : changed) {
        if (!is_changed[std::size_t(t)]) continue;  // listed twice in `changed`
        is_changed[std::size_t(t)] = 0;
        RowBox& box = triangle_rows_[std::size_t(t)];
        box = rows_of(vertices, triangles, t);
        for_each_row(box, [&](std::int64_t row) {
            flag(row);
            row_triangles_[std::size_t(row)].push_back(t);
        });
    }
    std::sort(rows.begin(), rows.end());
    classify(vertices, triangles, rows);
    return rows;
}

VoxelCentresInside::RowBox VoxelCentresInside::rows_of(const PointMatrix& v, const FaceMatrix& triangles,
                                                      Eigen::Index t) const {
    double y0 = v(triangles(t, 0), 1), y1 = y0, z0 = v(triangles(t, 0), 2), z1 = z0;
    for (int k = 1; k < 3; ++k) {
        y0 = std::min(y0, v(triangles(t, k), 1)), y1 = std::max(y1, v(triangles(t, k), 1));
        z0 = std::min(z0, v(triangles(t, k), 2)), z1 = std::max(z1, v(triangles(t, k), 2));
    }
    const auto [j0, j1] = row_range(y0, y1, grid_.origin.y(), grid_.spacing.y(), grid_.dims[1]);
    const auto [k0, k1] = row_range(z0, z1, grid_.origin.z(), grid_.spacing.z(), grid_.dims[2]);
    return RowBox{std::int32_t(j0), std::int32_t(j1), std::int32_t(k0), std::int32_t(k1)};
}

template <class Visit>
void VoxelCentresInside::for_each_row(const RowBox& box, Visit visit) const {
    const std::int64_t ny = grid_.dims[1];
    for (std::int64_t k = box.k0; k <= box.k1; ++k)
        for (std::int64_t j = box.j0; j <= box.j1; ++j) visit(j + ny * k);
}

void VoxelCentresInside::classify(const PointMatrix& vertices, const FaceMatrix& triangles,
                                  const std::vector<std::int64_t>& rows) {
    const std::int64_t ny = grid_.dims[1];
#pragma omp parallel
    {
        std::vector<double> crossings;
#pragma omp for schedule(dynamic, 16)
        for (std::size_t r = 0; r < rows.size(); ++r) {
            const std::int64_t row = rows[r], j = row % ny, k = row / ny;
            const std::vector<std::int32_t>& listed = row_triangles_[std::size_t(row)];
            classify_row(vertices, triangles, grid_, j, k, listed.data(), listed.data() + listed.size(), crossings,
                         bits_.data() + row * words_per_row_);
        }
    }
}

std::vector<std::uint8_t> VoxelCentresInside::inside() const {
    std::vector<std::uint8_t> bytes(std::size_t(grid_.voxel_count()));
#pragma omp parallel for schedule(static)
    for (std::int64_t v = 0; v < grid_.voxel_count(); ++v) bytes[std::size_t(v)] = is_inside(v) ? 1 : 0;
    return bytes;
}

std::vector<std::uint8_t> voxel_centres_inside(const PointMatrix& vertices, const FaceMatrix& triangles,
                                               const VoxelGrid& grid) {
    return VoxelCentresInside(vertices, triangles, grid).inside();
}

}  // namespace dsreg
