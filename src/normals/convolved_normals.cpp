// Convolved trivial normals (see normals.hpp), over the faces of one interface on a label
// complex: surfel centres are binned into cubic cells of
// side ≥ r, so every neighbour within r of a surfel lies in the 3×3×3 block of cells around
// its own. Cost: O(m log m) for the binning, then O(r²/h²) per surfel on a surface.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "dsreg/error.hpp"
#include "dsreg/normals.hpp"

namespace dsreg {

namespace {

/// A cell of the binning, within one interface: (interface, x, y, z). A binary surface is one
/// interface; on a label complex each pair of labels is one, so that a face's neighbours are
/// looked up among the faces of its own interface only.
using Cell = std::array<std::int64_t, 4>;

/// Surfels sorted by cell; cells[c] holds surfels order[first[c] .. first[c+1]).
struct CellBins {
    std::vector<Cell> cells;            ///< occupied cells, sorted
    std::vector<std::int64_t> first;    ///< size cells.size() + 1
    std::vector<std::int32_t> order;    ///< surfel indices grouped by cell
};

/// The interface of face f: 0 on a binary surface, else its pair of labels as one number.
std::int64_t interface_of(const DigitalSurface& surface, std::int64_t f) {
    if (surface.face_labels.empty()) return 0;
    const FaceLabels& l = surface.face_labels[std::size_t(f)];
    return std::int64_t(l.inner) * surface.label_count() + l.outer;
}

CellBins bin_centres(const DigitalSurface& surface, const PointMatrix& centres, double cell_size) {
    const std::int64_t m = centres.rows();
    const Eigen::RowVector3d low = centres.colwise().minCoeff();
    std::vector<Cell> cell(static_cast<std::size_t>(m));
    for (std::int64_t f = 0; f < m; ++f) {
        cell[std::size_t(f)][0] = interface_of(surface, f);
        for (int d = 0; d < 3; ++d)
            cell[std::size_t(f)][std::size_t(d + 1)] = std::int64_t(std::floor((centres(f, d) - low[d]) / cell_size));
    }
    CellBins bins;
    bins.order.resize(std::size_t(m));
    std::iota(bins.order.begin(), bins.order.end(), 0);
    std::stable_sort(bins.order.begin(), bins.order.end(),
                     [&](std::int32_t a, std::int32_t b) { return cell[std::size_t(a)] < cell[std::size_t(b)]; });
    for (std::size_t q = 0; q < bins.order.size(); ++q) {
        const Cell& c = cell[std::size_t(bins.order[q])];
        if (bins.cells.empty() || bins.cells.back() != c) {
            bins.cells.push_back(c);
            bins.first.push_back(std::int64_t(q));
        }
    }
    bins.first.push_back(m);
    return bins;
}

/// The occupied cells among the 27 around cells[c], in its interface.
std::vector<std::int64_t> neighbour_cells(const CellBins& bins, std::int64_t c) {
    std::vector<std::int64_t> found;
    const Cell& centre = bins.cells[std::size_t(c)];
    for (std::int64_t dx = -1; dx <= 1; ++dx)
        for (std::int64_t dy = -1; dy <= 1; ++dy)
            for (std::int64_t dz = -1; dz <= 1; ++dz) {
                const Cell key{centre[0], centre[1] + dx, centre[2] + dy, centre[3] + dz};
                const auto it = std::lower_bound(bins.cells.begin(), bins.cells.end(), key);
                if (it != bins.cells.end() && *it == key) found.push_back(it - bins.cells.begin());
            }
    return found;
}

}  // namespace

namespace {

/// Convolved trivial normals of the faces f with wanted(f) (all if `wanted` is empty), written
/// into u; the other rows of u are left alone.
void convolve_trivial_normals(const DigitalSurface& surface, double radius, IntegralInvariantKernel kernel,
                              const std::vector<char>& wanted, PointMatrix& u) {
    if (!(radius > 0) || !std::isfinite(radius))
        throw Error("convolved trivial normals: radius must be positive and finite (got " + std::to_string(radius) + ")");
    const PointMatrix centres = surfel_centers(surface);
    // Distinct surfel centres are at least half a voxel apart, so cells need not be much smaller
    // than a voxel even for a tiny radius (which keeps the cell coordinates small).
    const double cell_size = std::max(radius, 0.25 * surface.grid.spacing.minCoeff());
    const CellBins bins = bin_centres(surface, centres, cell_size);
    const double r2 = radius * radius;
    // Each trivial normal weighs its face's area: on an anisotropic grid the faces across axis a
    // are spacing_b·spacing_c large, and the area-weighted sum of the trivial normals over a
    // patch is its flux, which points along the patch's normal whatever the spacing.
    const Eigen::Vector3d& h = surface.grid.spacing;
    const Eigen::Vector3d area(h.y() * h.z(), h.x() * h.z(), h.x() * h.y());
#pragma omp parallel for schedule(dynamic, 16)
    for (std::int64_t c = 0; c < std::int64_t(bins.cells.size()); ++c) {
        bool any = wanted.empty();
        for (std::int64_t q = bins.first[std::size_t(c)]; q < bins.first[std::size_t(c) + 1] && !any; ++q)
            any = wanted[std::size_t(bins.order[std::size_t(q)])] != 0;
        if (!any) continue;
        const std::vector<std::int64_t> around = neighbour_cells(bins, c);
        for (std::int64_t q = bins.first[std::size_t(c)]; q < bins.first[std::size_t(c) + 1]; ++q) {
            const std::int32_t f = bins.order[std::size_t(q)];
            if (!wanted.empty() && !wanted[std::size_t(f)]) continue;
            Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
            for (std::int64_t n : around)
                for (std::int64_t p = bins.first[std::size_t(n)]; p < bins.first[std::size_t(n) + 1]; ++p) {
                    const std::int32_t g = bins.order[std::size_t(p)];
                    const double d2 = (centres.row(g) - centres.row(f)).squaredNorm();
                    if (d2 > r2) continue;
                    const Surfel& s = surface.surfels[std::size_t(g)];
                    const double q2 = 1.0 - d2 / r2;
                    sum[s.axis] += (kernel == IntegralInvariantKernel::ball ? s.sign : s.sign * q2 * q2) * area[s.axis];
                }
            const double norm = sum.norm();
            // Opposite sides of a plate thinner than 2r can cancel out: keep the surfel's own normal.
            u.row(f) = norm > 1e-9 ? Eigen::RowVector3d(sum / norm)
                                   : Eigen::RowVector3d(surface.surfels[std::size_t(f)].trivial_normal().transpose());
        }
    }
}

}  // namespace

PointMatrix convolved_trivial_normals(const DigitalSurface& surface, double radius, IntegralInvariantKernel kernel) {
    PointMatrix u(surface.face_count(), 3);
    convolve_trivial_normals(surface, radius, kernel, {}, u);
    return u;
}

PointMatrix convolved_trivial_normals(const DigitalSurface& surface, double radius) {
    return convolved_trivial_normals(surface, radius, IntegralInvariantKernel::ball);
}

std::int64_t use_interface_normals_near_junctions(const LabelVolume& volume, const DigitalSurface& surface, double radius,
                                                  PointMatrix& normals) {
    if (normals.rows() != surface.face_count())
        throw Error("interface normals: " + std::to_string(normals.rows()) + " normals for " +
                    std::to_string(surface.face_count()) + " faces");
    const std::vector<char> near = faces_near_junctions(volume, surface, radius);
    const std::int64_t count = std::count(near.begin(), near.end(), char(1));
    if (count > 0) convolve_trivial_normals(surface, radius, IntegralInvariantKernel::biweight, near, normals);
    return count;
}

}  // namespace dsreg
