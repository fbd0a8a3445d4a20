// dsreg — the self-contained HTML page (see html_view.hpp): checks the layers, computes what
// they can be coloured by, and writes the page: data as JSON plus base64 buffers, then three.js,
// OrbitControls and the viewer's script (embedded when dsreg is built).
#include "dsreg/html_view.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "dsreg/ambrosio_tortorelli.hpp"
#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/mesh_io.hpp"
#include "page_buffers.hpp"
#include "viewer_assets.hpp"

namespace dsreg {

Eigen::VectorXd face_deviation_degrees(const PointMatrix& vertices, const FaceMatrix& faces, const PointMatrix& u) {
    if (u.rows() != faces.rows())
        throw Error("face deviation: " + std::to_string(u.rows()) + " field vectors for " +
                    std::to_string(faces.rows()) + " faces");
    const PointMatrix normals = face_normals(vertices, faces);
    Eigen::VectorXd degrees(faces.rows());
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
        const Eigen::Vector3d n = normals.row(f).transpose(), field = u.row(f).transpose();
        const bool defined = n.squaredNorm() > 0 && field.squaredNorm() > 0 && field.allFinite();
        degrees[f] = defined ? angle_degrees(n, field) : std::numeric_limits<double>::quiet_NaN();
    }
    return degrees;
}

Eigen::VectorXd vertex_displacements(const PointMatrix& moved, const PointMatrix& original) {
    if (moved.rows() != original.rows())
        throw Error("displacement: " + std::to_string(moved.rows()) + " vertices against " +
                    std::to_string(original.rows()));
    return (moved - original).rowwise().norm();
}

namespace {

using viewer::PageBuffers;

constexpr const char* feature_map_name = "v";

std::string layer_context(const ViewLayer& layer, std::size_t index) {
    return "layer " + std::to_string(index + 1) + " '" + layer.name + "'";
}

void check_layer(const ViewLayer& layer, std::size_t index) {
    const std::string context = layer_context(layer, index);
    if (layer.mesh.faces.rows() == 0)
        throw Error(context + ": the mesh has no faces (" + std::to_string(layer.mesh.vertices.rows()) +
                    " vertices): nothing to show");
    check_mesh(context, layer.mesh);
    if (layer.digital) {
        check_mesh(context + ", digital surface", *layer.digital);
        if (layer.digital->vertices.rows() != layer.mesh.vertices.rows())
            throw Error(context + ": the digital surface has " + std::to_string(layer.digital->vertices.rows()) +
                        " vertices, the mesh " + std::to_string(layer.mesh.vertices.rows()) +
                        " (vertex i of both must be the same point before and after regularization)");
    }
    if (layer.face_labels.rows() != 0 && layer.face_labels.rows() != layer.mesh.faces.rows())
        throw Error(context + ": " + std::to_string(layer.face_labels.rows()) + " label pairs for " +
                    std::to_string(layer.mesh.faces.rows()) + " faces");
}

std::int64_t face_count(const ViewLayer& layer) {
    return layer.mesh.faces.rows() + (layer.digital ? layer.digital->faces.rows() : 0);
}

void check_page(const ViewPage& page) {
    if (page.layers.empty()) throw Error("HTML view: no mesh to show");
    std::int64_t faces = 0;
    for (std::size_t i = 0; i < page.layers.size(); ++i) {
        check_layer(page.layers[i], i);
        faces += face_count(page.layers[i]);
    }
    if (faces > page.max_faces)
        throw Error("HTML view: " + std::to_string(faces) + " faces in all, more than a page can show (at most " +
                    std::to_string(page.max_faces) + ": a browser would take long and need gigabytes to open it)");
}

/// Centre of the bounding box of every vertex of every layer.
Eigen::Vector3d page_centre(const ViewPage& page) {
    Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), high = -low;
    const auto extend = [&](const PointMatrix& points) {
        if (points.rows() == 0) return;
        low = low.cwiseMin(points.colwise().minCoeff().transpose());
        high = high.cwiseMax(points.colwise().maxCoeff().transpose());
    };
    for (const ViewLayer& layer : page.layers) {
        extend(layer.mesh.vertices);
        if (layer.digital) extend(layer.digital->vertices);
    }
    return low.allFinite() && high.allFinite() ? Eigen::Vector3d((low + high) / 2) : Eigen::Vector3d::Zero();
}

/// Colour range of a field: [0, 99th percentile] for angles and lengths (so that a few large
/// values do not wash out the rest; at least 0.1 degree, or the largest length), [0, 1] for the
/// feature map, [min, max] for other scalars. NaNs are left out.
std::pair<double, double> colour_range(const Eigen::VectorXd& values, const std::string& kind) {
    if (kind == "feature_map") return {0.0, 1.0};
    std::vector<double> finite;
    finite.reserve(std::size_t(values.size()));
    for (Eigen::Index i = 0; i < values.size(); ++i)
        if (std::isfinite(values[i])) finite.push_back(values[i]);
    if (finite.empty()) return {0.0, 1.0};
    const auto [low, high] = std::minmax_element(finite.begin(), finite.end());
    if (kind == "scalar") return {*low, *high > *low ? *high : *low + 1};
    const double largest = *high;
    const std::size_t at = std::min(finite.size() - 1, std::size_t(0.99 * double(finite.size())));
    std::nth_element(finite.begin(), finite.begin() + std::ptrdiff_t(at), finite.end());
    const double p99 = finite[at];
    if (kind == "angle") return {0.0, std::max(0.1, p99)};
    return {0.0, p99 > 0 ? p99 : largest > 0 ? largest : 1.0};  // lengths
}

nlohmann::json field_json(PageBuffers& buffers, const std::string& name, const std::string& kind,
                          const std::string& unit, const Eigen::VectorXd& values) {
    const auto [low, high] = colour_range(values, kind);
    return {{"name", name}, {"kind", kind}, {"unit", unit}, {"range", {low, high}},
            {"buffer", buffers.add(viewer::float32_values(values))}};
}

nlohmann::json faces_json(PageBuffers& buffers, const FaceMatrix& faces) {
    return buffers.add(viewer::integer_matrix("uint32", faces.data(), faces.size()));
}

nlohmann::json summary_json(const std::vector<SummaryLine>& lines) {
    nlohmann::json list = nlohmann::json::array();
    for (const SummaryLine& line : lines) list.push_back({line.name, line.value});
    return list;
}

/// The edges of the feature lines of `v`, as vertex index pairs (Uint32).
nlohmann::json feature_edges_json(PageBuffers& buffers, const FaceMatrix& faces, const Eigen::VectorXd& v,
                                  double threshold) {
    std::vector<std::int32_t> pairs;
    for (const std::vector<std::int32_t>& line : feature_polylines(faces, v.size(), v, threshold))
        for (std::size_t i = 0; i + 1 < line.size(); ++i) pairs.insert(pairs.end(), {line[i], line[i + 1]});
    return buffers.add(viewer::integer_matrix("uint32", pairs.data(), std::int64_t(pairs.size())));
}

nlohmann::json labels_json(PageBuffers& buffers, const FaceLabelMatrix& labels) {
    const std::set<std::int32_t> values(labels.data(), labels.data() + labels.size());
    return {{"buffer", buffers.add(viewer::integer_matrix("int32", labels.data(), labels.size()))},
            {"values", std::vector<std::int32_t>(values.begin(), values.end())}};
}

/// A surface of a layer: positions, faces and the per-face fields that apply to it.
nlohmann::json surface_json(PageBuffers& buffers, const PolygonMesh& surface, const ViewLayer& layer,
                            const Eigen::Vector3d& centre) {
    nlohmann::json json = {{"vertex_count", surface.vertices.rows()},
                           {"face_count", surface.faces.rows()},
                           {"face_size", surface.faces.cols()},
                           {"positions", buffers.add(viewer::float32_points(surface.vertices, centre))},
                           {"faces", faces_json(buffers, surface.faces)}};
    // Face i of the digital surface is face i of the mesh only when both have as many faces.
    const bool same_faces = surface.faces.rows() == layer.mesh.faces.rows();
    if (same_faces && layer.mesh.face_normals.rows() > 0)
        json["deviation"] = field_json(buffers, "deviation", "angle", "degrees",
                                       face_deviation_degrees(surface.vertices, surface.faces, layer.mesh.face_normals));
    if (same_faces && layer.face_labels.rows() > 0) json["labels"] = labels_json(buffers, layer.face_labels);
    return json;
}

nlohmann::json layer_json(PageBuffers& buffers, const ViewLayer& layer, const ViewPage& page,
                          const Eigen::Vector3d& centre) {
    nlohmann::json json = {{"name", layer.name}, {"summary", summary_json(layer.summary)}};
    json["surface"] = surface_json(buffers, layer.mesh, layer, centre);
    nlohmann::json fields = nlohmann::json::array();  // per-vertex colour modes
    if (layer.digital) {
        json["digital"] = surface_json(buffers, *layer.digital, layer, centre);
        fields.push_back(field_json(buffers, "displacement |p* - p|", "length", page.length_unit,
                                    vertex_displacements(layer.mesh.vertices, layer.digital->vertices)));
    }
    for (const auto& [name, values] : layer.mesh.vertex_scalars) {
        const bool feature_map = name == feature_map_name;
        fields.push_back(field_json(buffers, feature_map ? "feature map v" : name,
                                    feature_map ? "feature_map" : "scalar", "", values));
        if (feature_map)
            json["feature_edges"] = feature_edges_json(buffers, layer.mesh.faces, values, page.feature_threshold);
    }
    json["vertex_fields"] = fields;
    return json;
}

/// JSON text that is safe inside a <script> element: '<' only occurs inside JSON strings, where
/// \u003c means the same, so "</script>" or "<!--" in a name cannot end or change the element.
std::string script_safe_json(const nlohmann::json& json) {
    const std::string text = json.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    std::string safe;
    safe.reserve(text.size());
    for (char c : text) {
        if (c == '<') safe += "\\u003c";
        else safe += c;
    }
    return safe;
}

}  // namespace

void write_html_view(std::ostream& out, const ViewPage& page) {
    check_page(page);
    const Eigen::Vector3d centre = page_centre(page);
    PageBuffers buffers;
    nlohmann::json data = {{"title", page.title},
                           {"summary", summary_json(page.summary)},
                           {"centre", {centre.x(), centre.y(), centre.z()}},
                           {"feature_threshold", page.feature_threshold},
                           {"three_revision", viewer_assets::three_revision}};
    nlohmann::json layers = nlohmann::json::array();
    for (const ViewLayer& layer : page.layers) layers.push_back(layer_json(buffers, layer, page, centre));
    data["layers"] = layers;
    data["buffers"] = buffers.manifest();

    out << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        // Nothing may be loaded from anywhere: the page is complete as it is.
        << "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; "
           "script-src 'unsafe-inline'; style-src 'unsafe-inline'\">\n"
        << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
        << "<meta name=\"generator\" content=\"dsreg\">\n<title>dsreg</title>\n"
        << "<style>\n" << viewer_assets::viewer_css << "</style>\n</head>\n<body>\n"
        << "<script>\n" << viewer_assets::errors_js << "</script>\n"
        << "<script type=\"application/json\" id=\"dsreg-page\">" << script_safe_json(data) << "</script>\n";
    buffers.write_elements(out);
    out << "<script id=\"dsreg-three\">\n/*\n" << viewer_assets::licence << "\n*/\n" << viewer_assets::three_js
        << "\n</script>\n<script id=\"dsreg-orbit-controls\">\n" << viewer_assets::orbit_controls_js
        << "\n</script>\n<script id=\"dsreg-viewer\">\n" << viewer_assets::viewer_js << "</script>\n</body>\n</html>\n";
}

void write_html_view(const std::string& path, const ViewPage& page) {
    try {
        check_page(page);  // before the temporary file is created
    } catch (const Error& e) {
        throw Error(path + ": " + e.what());
    }
    write_file_atomically(path, [&](std::ostream& out) { write_html_view(out, page); });
}

}  // namespace dsreg
