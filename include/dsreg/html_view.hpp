// dsreg — a self-contained HTML page that shows meshes in 3D (WebGL).
//
// write_html_view writes one HTML file that any browser opens from disk with no network: three.js
// r111 and its OrbitControls (Debian's libjs-three, embedded into dsreg when it is built), the
// viewer's script and style (src/viewer/), and the meshes as base64 binary buffers (little-endian
// Float32 / Uint32 / Int32) are all inside it, and a Content-Security-Policy forbids the page to
// load anything at all. docs/viewer.md describes the page.
//
// What the page shows, per layer (one ViewLayer each; one layer is visible at a time, the camera
// stays when switching, so layers of the same object compare by flicking between them):
//  * the surface (`mesh`), smooth-shaded; its wireframe (the faces' edges, quads stay quads);
//  * the digital surface (`digital`), flat-shaded, as a toggle;
//  * colour by: plain; normal-field deviation per face: the angle in degrees between the face's
//    normal (evaluation.hpp face_normals: the paper's footnote 5 for quads) and its row of
//    mesh.face_normals (u), NaN for a face without normal; displacement per vertex |p* − p|
//    between `mesh` and `digital` (mesh units); any vertex scalar of the mesh, the one named "v"
//    being the Ambrosio–Tortorelli feature map, drawn with its feature lines (the edges whose two
//    ends have v < feature_threshold, as ambrosio_tortorelli.hpp feature_polylines); labels;
//  * a colour legend with units, and the page's and the layer's summary lines in a corner.
//
// Positions are sent as Float32 relative to the centre of the bounding box of all layers (so
// that coordinates far from the origin keep their precision); every length shown is in the
// meshes' own units.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "dsreg/mesh.hpp"

namespace dsreg {

/// One (inside, outside) pair of integer labels per face, e.g. the two regions a face of a
/// multi-label surface separates: column 0 is the label of the region behind the face (opposite
/// to its normal: the region it bounds), column 1 the label of the region in front of it. Seen
/// from its front a face shows the colour of column 0, seen from behind that of column 1.
using FaceLabelMatrix = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 2, Eigen::RowMajor>;

/// One line of a summary box: a name and its value as text ("surfels", "37590").
struct SummaryLine {
    std::string name;
    std::string value;
};

/// One surface of the page, with what it can be coloured by.
struct ViewLayer {
    std::string name;  ///< shown in the layer list (UTF-8; invalid bytes are shown as U+FFFD)
    /// Vertices, faces (triangles or quads, at least one face); face_normals (u, one unit
    /// vector per face) enables the deviation colours; each vertex scalar becomes a colour mode.
    PolygonMesh mesh;
    /// The digital surface the mesh was regularized from: the same number of vertices (vertex i
    /// of both is the same point before and after), any faces. Enables the displacement colours;
    /// when it has as many faces as `mesh`, face i of both is taken to be the same face (the
    /// deviation and labels then colour it too).
    std::optional<PolygonMesh> digital;
    FaceLabelMatrix face_labels;        ///< empty, or one row per face of `mesh`
    std::vector<SummaryLine> summary;  ///< e.g. the file, its counts
};

/// Most faces (all layers, surfaces and digital surfaces together) write_html_view accepts by
/// default. Measured (docs/viewer.md): 4·10^6 quads with their digital surface (8·10^6 faces)
/// make a 278 MB page that headless Chromium shows 8 s after opening it; beyond, pages get
/// slow to open and need gigabytes in the browser.
constexpr std::int64_t kDefaultMaxViewFaces = 8'000'000;

struct ViewPage {
    std::string title;                 ///< page title and heading (UTF-8)
    std::vector<ViewLayer> layers;     ///< at least one
    std::vector<SummaryLine> summary;  ///< the run's summary (input, counts, parameters, times)
    double feature_threshold = 0.5;    ///< v below which a vertex is on a feature line
    std::string length_unit = "mesh units";  ///< unit of lengths in the legend (displacement)
    std::int64_t max_faces = kDefaultMaxViewFaces;
};

/// Per face: the angle in degrees (0 … 180) between the face's normal (face_normals of
/// evaluation.hpp) and its row of `u`; NaN for a face without normal (no area) or a zero row of
/// u. Throws dsreg::Error unless u has one row per face.
Eigen::VectorXd face_deviation_degrees(const PointMatrix& vertices, const FaceMatrix& faces, const PointMatrix& u);

/// Per vertex: |moved_i − original_i| (physical units). Throws dsreg::Error unless both have as
/// many rows.
Eigen::VectorXd vertex_displacements(const PointMatrix& moved, const PointMatrix& original);

/// Writes the page as HTML to `out`. Throws dsreg::Error naming the layer for a layer without
/// faces, with faces other than triangles or quads, indices out of range, non-finite
/// coordinates, attributes of the wrong size, more faces in all than page.max_faces, or no
/// layer at all.
void write_html_view(std::ostream& out, const ViewPage& page);

/// Writes the page to `path` (atomic: a failure leaves no file and an existing one untouched).
/// Throws dsreg::Error naming `path` (or the layer) on failure.
void write_html_view(const std::string& path, const ViewPage& page);

}  // namespace dsreg
