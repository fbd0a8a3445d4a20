// dsreg — validity of a quad mesh kept up to date while some of its vertices move (internal to
// src/validity): after a move only the triangles of the moved vertices and the triangles near them
// in space are tested again, instead of the whole mesh.
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "dsreg/digital_surface.hpp"  // VertexCorners
#include "dsreg/mesh.hpp"
#include "dsreg/mesh_validity.hpp"

namespace dsreg::validity_internal {

class IncrementalValidity {
public:
    /// Checks the whole mesh (quads) once, with the field (one vector per quad).
    IncrementalValidity(const PointMatrix& vertices, const FaceMatrix& quads, const PointMatrix& field);
    ~IncrementalValidity();

    /// The vertices in `moved` have new positions in `vertices`, and the quads in `refield` a new
    /// field vector: tests again what they can have changed. Same result as check_mesh_validity
    /// on the whole mesh.
    void update(const PointMatrix& vertices, const std::vector<std::int32_t>& moved,
                const std::vector<std::int32_t>& refield, const PointMatrix& field);

    /// The current state as check_mesh_validity reports it (seconds: of all checks so far).
    MeshValidity validity() const;

    /// The quads around each vertex (vertex_corners of the quads).
    const VertexCorners& corners() const { return corners_; }

private:
    class BoxGrid;

    void retest(const PointMatrix& vertices, const std::vector<std::int32_t>& quads_to_test, const PointMatrix& field);

    const FaceMatrix& quads_;
    VertexCorners corners_;  ///< the quads around each vertex
    FaceMatrix triangles_;  ///< 2q, 2q + 1: the shorter-diagonal split of quad q (current positions)
    std::vector<std::pair<std::int64_t, std::int64_t>> pairs_;  ///< intersecting triangles, sorted
    std::vector<char> degenerate_;                               ///< per triangle
    std::vector<char> folded_;                                   ///< per quad
    std::unique_ptr<BoxGrid> grid_;  ///< the triangles' boxes, from the first update on
    double seconds_ = 0;
};

}  // namespace dsreg::validity_internal
