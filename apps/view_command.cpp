#include "view_command.hpp"

#include <cstdint>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "dsreg/error.hpp"
#include "dsreg/html_view.hpp"
#include "dsreg/mesh_io.hpp"
#include "dsreg/output_paths.hpp"

namespace dsreg::cli {

namespace {

struct ViewOptions {
    std::vector<std::string> meshes;
    std::string digital, output, title;
    double feature_threshold = 0.5;
    std::int64_t max_faces = kDefaultMaxViewFaces;
    bool quiet = false;
};

/// What the page can colour a mesh by, for its summary.
std::string attributes_line(const PolygonMesh& mesh) {
    std::string text;
    const auto add = [&](const std::string& item) { text += (text.empty() ? "" : ", ") + item; };
    if (mesh.face_normals.rows() > 0) add("normal field u per face");
    for (const auto& [name, values] : mesh.vertex_scalars) add(name == "v" ? "feature map v" : name + " per vertex");
    for (const auto& [name, values] : mesh.face_integers) add(name + " per face");
    return text.empty() ? "none" : text;
}

/// The face integers called `name`, or null.
const Eigen::VectorXi* face_integers(const PolygonMesh& mesh, const std::string& name) {
    for (const auto& [key, values] : mesh.face_integers)
        if (key == name) return &values;
    return nullptr;
}

ViewLayer read_layer(const std::string& path) {
    ViewLayer layer;
    layer.name = std::filesystem::path(path).filename().string();
    layer.mesh = read_mesh(path);
    layer.summary = {{"file", path}, {"attributes", attributes_line(layer.mesh)}};
    // A label complex written by regularize --multi-label (PLY face properties, VTK cell data):
    // each face seen from its front shows its inner label, from behind its outer label.
    const Eigen::VectorXi* inner = face_integers(layer.mesh, "inner_label");
    const Eigen::VectorXi* outer = face_integers(layer.mesh, "outer_label");
    if (inner != nullptr && outer != nullptr) {
        layer.face_labels.resize(inner->size(), 2);
        layer.face_labels.col(0) = *inner;
        layer.face_labels.col(1) = *outer;
    }
    return layer;
}

void run(const ViewOptions& o) {
    check_page_output_path("-o", o.output);
    ViewPage page;
    page.feature_threshold = o.feature_threshold;
    page.max_faces = o.max_faces;
    for (const std::string& path : o.meshes) page.layers.push_back(read_layer(path));
    if (!o.digital.empty()) {
        const PolygonMesh digital = read_mesh(o.digital);
        int paired = 0;
        for (ViewLayer& layer : page.layers)
            if (layer.mesh.vertices.rows() == digital.vertices.rows()) {
                layer.digital = digital;
                layer.summary.push_back({"digital surface", o.digital});
                ++paired;
            }
        if (paired == 0)
            throw Error("--digital " + o.digital + ": " + std::to_string(digital.vertices.rows()) +
                        " vertices, but no mesh given has as many (it must be the digital surface the mesh was "
                        "regularized from, e.g. written by regularize --input-mesh)");
    }
    page.title = o.title;
    if (page.title.empty())
        for (const ViewLayer& layer : page.layers) page.title += (page.title.empty() ? "" : ", ") + layer.name;
    write_html_view(o.output, page);
    if (!o.quiet) std::cerr << "dsreg: " << page.layers.size() << (page.layers.size() == 1 ? " mesh" : " meshes")
                            << " -> " << o.output << '\n';
}

}  // namespace

void add_view_command(CLI::App& app) {
    auto options = std::make_shared<ViewOptions>();
    CLI::App* cmd = app.add_subcommand(
        "view", "Write one self-contained HTML page showing meshes in 3D (any browser, no network needed)");
    cmd->add_option("meshes", options->meshes,
                    "Mesh files: .obj .off .ply .stl .vtk .vtp; each is a layer of the page (a PLY, VTK or VTP written "
                    "by dsreg carries the normal field u per face and the feature map v per vertex)")
        ->required();
    cmd->add_option("-o,--output", options->output, "The page: .html")->required();
    cmd->add_option("--digital", options->digital,
                    "The digital surface the meshes were regularized from (regularize --input-mesh): shown as a "
                    "toggle, and colours by displacement |p* - p|, for each mesh with as many vertices");
    cmd->add_option("--title", options->title, "Title of the page (default: the file names)");
    cmd->add_option("--feature-threshold", options->feature_threshold,
                    "Feature lines: the edges whose two ends have a feature map v below this")
        ->capture_default_str();
    cmd->add_option("--max-faces", options->max_faces,
                    "Refuse pages with more faces in all (meshes and digital surfaces): larger pages take long to "
                    "open and gigabytes in the browser (docs/viewer.md)")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    cmd->add_flag("-q,--quiet", options->quiet, "Print nothing but errors");
    cmd->callback([options] { run(*options); });
}

}  // namespace dsreg::cli
