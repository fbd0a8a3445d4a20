// dsreg — which voxel centres lie inside a closed triangle mesh: parity of ray crossings along
// +x, one sorted list of crossings per voxel row.
#include <algorithm>
#include <cmath>

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

/// Triangles listed per voxel row (j, k) of the grid, row index j + ny·k, in compressed form.
struct RowBuckets {
    std::vector<std::int64_t> offsets;
    std::vector<std::int32_t> triangles;
};

/// Range of row indices whose coordinate origin + spacing·index lies in [low, high], widened by
/// one row on each side against rounding (the exact test decides).
std::pair<std::int64_t, std::int64_t> row_range(double low, double high, double origin, double spacing,
                                                std::int64_t count) {
    const double first = std::ceil((low - origin) / spacing) - 1.0;
    const double last = std::floor((high - origin) / spacing) + 1.0;
    const std::int64_t lo = std::int64_t(std::clamp(first, 0.0, double(count)));
    const std::int64_t hi = std::int64_t(std::clamp(last, -1.0, double(count - 1)));
    return {lo, hi};
}

/// Calls visit(j + ny·k) for each voxel row (j, k) whose ray may cross triangle t.
template <class Visit>
void for_each_row_of_triangle(const PointMatrix& v, const FaceMatrix& triangles, Eigen::Index t, const VoxelGrid& grid,
                              Visit visit) {
    const std::int64_t ny = grid.dims[1], nz = grid.dims[2];
    double y0 = v(triangles(t, 0), 1), y1 = y0, z0 = v(triangles(t, 0), 2), z1 = z0;
    for (int k = 1; k < 3; ++k) {
        y0 = std::min(y0, v(triangles(t, k), 1)), y1 = std::max(y1, v(triangles(t, k), 1));
        z0 = std::min(z0, v(triangles(t, k), 2)), z1 = std::max(z1, v(triangles(t, k), 2));
    }
    const auto [j0, j1] = row_range(y0, y1, grid.origin.y(), grid.spacing.y(), ny);
    const auto [k0, k1] = row_range(z0, z1, grid.origin.z(), grid.spacing.z(), nz);
    for (std::int64_t k = k0; k <= k1; ++k)
        for (std::int64_t j = j0; j <= j1; ++j) visit(j + ny * k);
}

/// The triangles bucketed by row; with `rows` (one flag per row j + ny·k), only those rows.
RowBuckets bucket_triangles_by_row(const PointMatrix& v, const FaceMatrix& triangles, const VoxelGrid& grid,
                                   const std::vector<char>* rows = nullptr) {
    const std::int64_t ny = grid.dims[1], nz = grid.dims[2];
    RowBuckets buckets;
    buckets.offsets.assign(std::size_t(ny * nz + 1), 0);
    auto for_each_row = [&](Eigen::Index t, auto&& visit) {
        for_each_row_of_triangle(v, triangles, t, grid, [&](std::int64_t row) {
            if (!rows || (*rows)[std::size_t(row)]) visit(row);
        });
    };
    for (Eigen::Index t = 0; t < triangles.rows(); ++t)
        for_each_row(t, [&](std::int64_t row) { buckets.offsets[std::size_t(row + 1)] += 1; });
    for (std::size_t r = 1; r < buckets.offsets.size(); ++r) buckets.offsets[r] += buckets.offsets[r - 1];
    buckets.triangles.resize(std::size_t(buckets.offsets.back()));
    std::vector<std::int64_t> next(buckets.offsets.begin(), buckets.offsets.end() - 1);
    for (Eigen::Index t = 0; t < triangles.rows(); ++t)
        for_each_row(t, [&](std::int64_t row) { buckets.triangles[std::size_t(next[std::size_t(row)]++)] = std::int32_t(t); });
    return buckets;
}

void check_triangles(const PointMatrix& vertices, const FaceMatrix& triangles, const char* caller) {
    if (triangles.rows() > 0 && triangles.cols() != 3) throw Error(std::string(caller) + ": the faces must be triangles");
    for (Eigen::Index t = 0; t < triangles.rows(); ++t)
        for (int k = 0; k < 3; ++k)
            if (triangles(t, k) < 0 || triangles(t, k) >= vertices.rows())
                throw Error(std::string(caller) + ": triangle " + std::to_string(t) + " has a vertex index out of range");
}

/// Classifies the voxel centres of the rows (all of them, or those flagged in `rows`) into
/// `inside` (the grid's size; each row done is written whole).
void classify_rows(const PointMatrix& vertices, const FaceMatrix& triangles, const VoxelGrid& grid,
                   const std::vector<char>* rows, std::vector<std::uint8_t>& inside) {
    const std::int64_t nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
    const RowBuckets buckets = bucket_triangles_by_row(vertices, triangles, grid, rows);

#pragma omp parallel
    {
        std::vector<double> crossings;
#pragma omp for schedule(dynamic, 16)
        for (std::int64_t k = 0; k < nz; ++k) {
            for (std::int64_t j = 0; j < ny; ++j) {
                const std::int64_t row = j + ny * k;
                if (rows && !(*rows)[std::size_t(row)]) continue;
                std::uint8_t* row_inside = inside.data() + grid.linear_index(0, j, k);
                std::fill(row_inside, row_inside + nx, std::uint8_t(0));
                const Eigen::Vector3d start = grid.voxel_center(0, j, k);
                const Point2 ray{start.y(), start.z()};
                crossings.clear();
                for (std::int64_t e = buckets.offsets[std::size_t(row)]; e < buckets.offsets[std::size_t(row + 1)]; ++e) {
                    double x;
                    if (ray_crossing(vertices, triangles, buckets.triangles[std::size_t(e)], ray, x)) crossings.push_back(x);
                }
                if (crossings.empty()) continue;
                std::sort(crossings.begin(), crossings.end());
                // Voxel i is inside iff an odd number of crossings lie beyond x_i: the voxels
                // between crossings p − 1 and p (x_{p−1} ≤ x_i < x_p) are inside iff m − p is odd.
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
                    if ((m - p) % 2 == 1 && to > from) std::fill(row_inside + from, row_inside + to, std::uint8_t(1));
                    from = std::max(from, to);
                }
            }
        }
    }
}

}  // namespace

std::vector<std::uint8_t> voxel_centres_inside(const PointMatrix& vertices, const FaceMatrix& triangles,
                                               const VoxelGrid& grid) {
    check_triangles(vertices, triangles, "voxel_centres_inside");
    std::vector<std::uint8_t> inside(std::size_t(grid.voxel_count()), 0);
    if (triangles.rows() == 0 || grid.voxel_count() == 0) return inside;
    classify_rows(vertices, triangles, grid, nullptr, inside);
    return inside;
}

void flag_rows_of_triangle(const PointMatrix& vertices, const FaceMatrix& triangles, Eigen::Index t, const VoxelGrid& grid,
                           std::vector<char>& rows) {
    for_each_row_of_triangle(vertices, triangles, t, grid, [&](std::int64_t row) { rows[std::size_t(row)] = 1; });
}

void update_voxel_centres_inside(const PointMatrix& vertices, const FaceMatrix& triangles, const VoxelGrid& grid,
                                 const std::vector<char>& rows, std::vector<std::uint8_t>& inside) {
    check_triangles(vertices, triangles, "update_voxel_centres_inside");
    if (std::int64_t(rows.size()) != grid.dims[1] * grid.dims[2] || std::int64_t(inside.size()) != grid.voxel_count())
        throw Error("update_voxel_centres_inside: one flag per voxel row and one value per voxel expected");
    classify_rows(vertices, triangles, grid, &rows, inside);
}

}  // namespace dsreg
