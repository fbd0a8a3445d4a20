// dsreg — the complex of a label map's interfaces (extract_digital_surface of a LabelVolume):
// its edges and junctions, the links of the fairness term of the joint regularization, and the
// closed surface of each label (docs/multi-label.md).
//
// Vocabulary. An *edge* of the complex is a class of face edges glued by some label's surface
// (at a linel, the pairing of every label whose faces meet there): a manifold edge has two
// faces, a *junction edge* has faces that separate three or more labels (three faces around a
// linel with three labels, or four). A *junction vertex* is an end point of a junction edge:
// where three or more regions meet, along a junction curve (two junction edges) or at a
// junction point (one, or three and more). Every other vertex lies inside one interface.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"

namespace dsreg {

struct ComplexEdges {
    std::vector<std::int32_t> of_face_edge;         ///< edge of face edge (f, e), at index 4f + e
    std::vector<std::array<std::int32_t, 2>> ends;  ///< the two vertices of each edge
    std::vector<std::uint8_t> face_count;           ///< face edges glued into it (2, 3 or 4)
    std::vector<char> junction;                     ///< its faces separate three or more labels

    std::int64_t count() const { return static_cast<std::int64_t>(ends.size()); }
};

ComplexEdges complex_edges(const DigitalSurface& surface);

/// Whether the surface can have junctions: it carries its faces' labels and surfels (a welded
/// block-wise surface does not) and separates three regions or more (a binary volume, or a map of
/// one label, has two: its complex is a manifold, its fairness links are the quad links).
bool may_have_junctions(const DigitalSurface& surface);

/// 1 for the end points of junction edges; the number of junction edges of each vertex.
struct Junctions {
    std::vector<char> vertex;
    std::vector<std::int32_t> edges_at_vertex;
    std::int64_t vertex_count = 0;  ///< junction vertices
    std::int64_t point_count = 0;   ///< junction vertices with other than two junction edges
    std::int64_t edge_count = 0;    ///< junction edges
};

Junctions find_junctions(const DigitalSurface& surface, const ComplexEdges& edges);

/// 1 for the vertices at the inner corner of a turn of a junction curve: corner k of a face whose
/// two edges at k are both junction edges. The face's other three corners lie on the curve too
/// (j₁ j₂ j₃ and one sheet vertex); once the curve is smoothed, j₂ lies near the chord j₁j₃ and the
/// corner triangle j₁j₂j₃ is a sliver between the curve and its staircase, which folds when j₂
/// ends a little on the inner side (docs/multi-label.md, "Validity"). None on a binary volume.
std::vector<char> junction_turn_vertices(const DigitalSurface& surface, const ComplexEdges& edges);

/// Fairness targets (RegularizationWeights::fairness_targets) that hold each turn of a junction
/// curve on the outer side of its chord (docs/multi-label.md, "Turns of junction curves"): at a
/// turn vertex j₂ (junction_turn_vertices) whose fairness links are its two neighbours j₁, j₃
/// along the curve, t = share · (p_j₂ − (p_j₁ + p_j₃)/2) at the digital positions p (physical
/// units: half a face diagonal times `share`); a zero row elsewhere. share = 0 asks for the chord
/// (the fairness as it is), 1 for the staircase's corner. Empty on a binary surface.
PointMatrix junction_turn_targets(const DigitalSurface& surface, const ComplexEdges& edges, const VertexLinks& links,
                                  double share);

/// Links of the fairness term (eq. 11–14) on the complex, one neighbour per edge:
///  * a vertex inside one interface: every edge (for a manifold complex, e.g. any binary
///    volume, exactly vertex_links(quads), in the same order);
///  * a junction vertex with two junction edges: only those two, so that the junction curve is
///    smoothed along its length and not rounded across (its neighbours in the sheets are not
///    averaged in);
///  * a junction point (one, or three or more junction edges): none, no fairness; alignment and
///    data place it.
/// A surface without face labels or surfels (a welded block-wise surface), or of two regions (a binary
/// volume, one label), gets vertex_links(quads) at once.
VertexLinks fairness_links(const DigitalSurface& surface);
/// The same for a surface with face labels and surfels, from its edges (complex_edges), for a
/// caller that needs them too.
VertexLinks fairness_links(const DigitalSurface& surface, const ComplexEdges& edges);

/// The closed surface of one label, made of faces and vertices of the complex, oriented outward
/// of the label. It is the label's own digital surface: its faces are those of the label's
/// indicator, paired the same way, and it has one vertex per umbrella. Where the label's surface
/// has several umbrellas at one vertex of the complex (a *pinch*: e.g. two voxels of the label
/// touching at a corner through which an interface of two other labels passes) its own vertices
/// share that vertex's position.
struct LabelMesh {
    std::uint32_t label = 0;              ///< label index (surface.label_values[label] is its value)
    std::vector<std::int64_t> faces;      ///< face of the complex of each face, increasing
    std::vector<std::uint8_t> reversed;   ///< 1 where the label is the outer label of the face
    FaceMatrix quads;                     ///< over the mesh's own vertices, counter-clockwise seen from outside
    std::vector<std::int32_t> vertices;   ///< vertex of the complex of each own vertex
    std::vector<std::int32_t> face_component;
    std::int32_t component_count = 0;
    std::int64_t pinch_vertices = 0;      ///< vertices of the complex carrying several own vertices

    std::int64_t face_count() const { return quads.rows(); }
    std::int64_t vertex_count() const { return static_cast<std::int64_t>(vertices.size()); }
    /// V − E + F of each component (E = 2F: the surface is closed).
    std::vector<std::int64_t> euler_characteristics() const;
};

/// The surface of every label with at least one face, in increasing label index.
std::vector<LabelMesh> label_meshes(const DigitalSurface& surface);

/// The mesh of a label over `positions` (one row per vertex of the complex), with the complex's
/// face normals `normals` (flipped where the label is the outer one) if given.
PolygonMesh label_polygon_mesh(const LabelMesh& mesh, const PointMatrix& positions, const PointMatrix& normals);

}  // namespace dsreg
