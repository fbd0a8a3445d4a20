// dsreg — internal: the mesh cut into independently solved parts.
//
// R of eq. (22–23) couples two vertices only if they share a face (the alignment term) or are
// within two links of each other (the fairness term), so it is block diagonal over the connected
// components of the graph of faces and links: each component's system can be solved on its own,
// with the same answer as the whole system. (The links are those R is built with: the quad links
// of a binary surface, the junction-aware fairness_links of a label complex, whose components
// are joined through their junctions.) Components of at most `small_vertices` vertices are gathered into
// parts of at most about `batch_vertices` vertices (solved directly: a sparse Cholesky factor of a
// block diagonal matrix is the union of the blocks' factors); every larger component is a part
// of its own. Real volumes have many tiny components (CT noise: lobster.vol has 417 of at most
// 218 vertices next to one of 256 448), which slow down a multigrid solver of the whole system
// (113 iterations on lobster against 60 for its large component alone, docs/solvers.md).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "dsreg/mesh.hpp"
#include "dsreg/progress.hpp"
#include "dsreg/regularization.hpp"

namespace dsreg::detail {

/// Components of at most this many vertices are solved directly, in batches of about
/// kBatchVertices vertices: amg's coarsest level has 400 nodes, so amg would factor them anyway.
constexpr std::int64_t kSmallComponentVertices = 400;
constexpr std::int64_t kBatchVertices = 20000;

struct MeshPart {
    std::vector<std::int32_t> vertices;  ///< global index of each local vertex, increasing
    std::vector<std::int32_t> faces;     ///< global index of each local face, increasing
    std::int32_t components = 0;         ///< connected components in the part
    bool small = false;                  ///< a batch of components of at most small_vertices vertices
    bool whole = false;                  ///< the part is the whole mesh (nothing to extract)
};

/// Cuts the mesh into parts (see above), largest part first. Every vertex and face is in exactly
/// one part, and every vertex's links are in its part; a vertex in no face and no link (not in a
/// digital surface) gets a part of small components.
std::vector<MeshPart> mesh_parts(const FaceMatrix& quads, const VertexLinks& links, std::int64_t vertex_count,
                                 std::int64_t small_vertices, std::int64_t batch_vertices);

/// The mesh of one part, with local vertex indices, and the part's rows of the per-vertex and
/// per-face data.
struct PartMesh {
    PointMatrix positions;
    FaceMatrix quads;
    VertexLinks links;
    PointMatrix normals;
    RegularizationWeights weights;
};
PartMesh extract_part(const MeshPart& part, const PointMatrix& positions, const FaceMatrix& quads, const VertexLinks& links,
                      const PointMatrix& normals, const RegularizationWeights& weights);

/// The mesh data of a part as the solvers see it: the whole mesh's own arrays when the part is the
/// whole mesh (nothing copied), else those of extract_part.
struct PartView {
    const PointMatrix& positions;
    const FaceMatrix& quads;
    const VertexLinks& links;
    const PointMatrix& normals;
    const RegularizationWeights& weights;
};
template <class Visit>
void visit_part(const MeshPart& part, const PointMatrix& positions, const FaceMatrix& quads, const VertexLinks& links,
                const PointMatrix& normals, const RegularizationWeights& weights, Visit visit) {
    if (part.whole) {
        visit(PartView{positions, quads, links, normals, weights});
        return;
    }
    const PartMesh mesh = extract_part(part, positions, quads, links, normals, weights);
    visit(PartView{mesh.positions, mesh.quads, mesh.links, mesh.normals, mesh.weights});
}

/// Progress of one part's solve mapped into [first, first + share] of the whole solve.
inline ProgressCallback progress_share(const ProgressCallback& progress, double first, double share) {
    if (!progress) return {};
    return [=](const ProgressEvent& e) {
        progress(ProgressEvent{e.stage, e.fraction < 0 ? -1.0 : first + share * e.fraction, e.detail});
    };
}

/// x restricted to the part's vertices (interleaved), and written back.
Eigen::VectorXd gather_part(const MeshPart& part, const Eigen::VectorXd& x);
void scatter_part(const MeshPart& part, const Eigen::VectorXd& local, Eigen::VectorXd& x);

}  // namespace dsreg::detail
