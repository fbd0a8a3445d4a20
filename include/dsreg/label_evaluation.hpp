// dsreg — how close the regularized complex of a label map is to a known partition
// (label_shapes.hpp): distances of the vertices to the true interfaces and junction curves, and
// per-label measures of the closed surfaces (docs/multi-label.md). Lengths in physical units.
#pragma once

#include <cstdint>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/label_shapes.hpp"
#include "dsreg/label_surface.hpp"
#include "dsreg/mesh.hpp"

namespace dsreg {

/// The label values around each vertex of the complex (those of its faces), increasing.
std::vector<std::vector<std::int64_t>> vertex_label_values(const DigitalSurface& surface);

struct LabelComplexErrors {
    /// Every vertex: distance to the nearest true interface between two of its labels.
    ErrorStats interfaces;
    /// Vertices inside one interface (two labels): distance to that interface.
    ErrorStats sheets;
    /// Junction vertices (three or more labels): distance to where all their labels meet (the
    /// true junction curve or point).
    ErrorStats junctions;
    /// Junction vertices whose labels do not all meet in the truth (left out of `junctions`).
    std::int64_t unmatched_junctions = 0;
};

LabelComplexErrors label_complex_errors(const LabelShape& shape, const DigitalSurface& surface,
                                        const PointMatrix& positions);

/// What the report says of one label's closed surface.
struct LabelMeasures {
    std::int64_t value = 0;         ///< the label's value in the input
    std::int64_t faces = 0, vertices = 0;
    double area = 0;                ///< of its quads split along the shorter diagonal
    double volume = 0;              ///< enclosed by its surface (divergence theorem, same triangles)
    double voxel_volume = 0;        ///< its voxels × the volume of one voxel
    std::int32_t components = 0;
    std::int64_t genus = 0;         ///< Σ over components of (2 − χ)/2 (a cavity counts as a sphere)
    std::vector<std::int64_t> euler_characteristics;
    std::int64_t pinch_vertices = 0;
};

/// The measures of a label's mesh at `positions` (one row per vertex of the complex).
LabelMeasures measure_label(const DigitalSurface& surface, const LabelMesh& mesh, const PointMatrix& positions,
                            std::int64_t voxel_count);

}  // namespace dsreg
