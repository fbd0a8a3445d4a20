// dsreg pipeline — the welded result of a block-wise run and its per-block fragments
// (include/dsreg/block_pipeline.hpp).
#include <filesystem>
#include <limits>

#include "dsreg/atomic_file.hpp"
#include "dsreg/block_pipeline.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/mesh_io.hpp"
#include "dsreg/text.hpp"
#include "pipeline_stages.hpp"

namespace dsreg {

namespace {

nlohmann::json box_json(const VoxelBox& box) { return {{"lo", box.lo}, {"hi", box.hi}}; }

}  // namespace

PipelineResult welded_pipeline_result(WeldedRun run, const BlockPlan& plan) {
    const PipelineOptions& o = plan.options;
    PipelineResult r;
    r.input = plan.header.description;
    r.grid = plan.header.volume.grid;
    r.file = plan.header.file;  // the world geometry the meshes are written in (--space)
    r.object_voxels = run.object_voxels;
    r.surface = std::move(run.welded.surface);
    r.field = std::move(run.field);
    r.field.normals = std::move(run.welded.normals);
    r.field.faces_against_surfels.clear();  // faces of one block's patch, not of the welded surface
    r.weights = RegularizationWeights{o.alpha, o.beta, o.gamma, {}, {}};
    apply_regularization_extensions(o.extensions, r.surface, r.field, ThinParts(), r.weights);  // no thin-part weights
    RegularizationResult& reg = r.regularization;
    reg.positions = std::move(run.welded.positions);
    reg.solve = run.solve;
    reg.assembly_seconds = run.assembly_seconds;
    reg.solve_seconds = run.solve_seconds;
    const VertexLinks links = vertex_links(r.surface.quads, r.surface.vertex_count());
    reg.energy_before = regularization_energy(r.surface.vertices, r.surface.vertices, r.surface.quads, links, r.field.normals, r.weights);
    reg.energy_after = regularization_energy(reg.positions, r.surface.vertices, r.surface.quads, links, r.field.normals, r.weights);
    r.faces_against_field = count_faces_against_field(reg.positions, r.surface.quads, r.field.normals);
    r.extension_report = {{"metric", o.extensions.metric},
                          {"local_weights", {{"alpha", nullptr}, {"beta", nullptr}, {"gamma", nullptr}}},
                          {"blocks", run.blocks}};
    r.stage_seconds = std::move(run.stage_seconds);
    return r;
}

void write_block_fragments(const std::string& folder, const PipelineResult& result, const BlockLayout& layout) {
    namespace fs = std::filesystem;
    std::error_code error;
    fs::create_directories(folder, error);
    if (error) throw Error("--fragments " + folder + ": cannot create the folder: " + error.message());
    const DigitalSurface& s = result.surface;
    const std::vector<std::int64_t> keys = vertex_keys_of(s, {0, 0, 0}, s.grid.dims);
    std::vector<std::vector<std::int32_t>> faces_of_block(static_cast<std::size_t>(layout.block_count()));
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        const auto& v = s.surfels[std::size_t(f)].voxel;
        faces_of_block[std::size_t(layout.block_of({v[0], v[1], v[2]}))].push_back(std::int32_t(f));
    }
    nlohmann::json blocks = nlohmann::json::array();
    std::vector<std::int32_t> local(static_cast<std::size_t>(s.vertex_count()), -1);
    for (std::int64_t block = 0; block < layout.block_count(); ++block) {
        const std::vector<std::int32_t>& faces = faces_of_block[std::size_t(block)];
        nlohmann::json entry = {{"block", block}, {"box", box_json(layout.box(block))}, {"faces", faces.size()}};
        if (faces.empty()) {
            entry["vertices"] = 0;
            entry["file"] = nullptr;
            blocks.push_back(entry);
            continue;
        }
        std::vector<std::int32_t> used;
        PolygonMesh mesh;
        mesh.faces.resize(std::int64_t(faces.size()), 4);
        mesh.face_normals.resize(std::int64_t(faces.size()), 3);
        for (std::size_t q = 0; q < faces.size(); ++q) {
            mesh.face_normals.row(std::int64_t(q)) = result.field.normals.row(faces[q]);
            for (int k = 0; k < 4; ++k) {
                const std::int32_t v = s.quads(faces[q], k);
                if (local[std::size_t(v)] < 0) local[std::size_t(v)] = std::int32_t(used.size()), used.push_back(v);
                mesh.faces(std::int64_t(q), k) = local[std::size_t(v)];
            }
        }
        mesh.vertices.resize(std::int64_t(used.size()), 3);
        Eigen::VectorXd key(std::int64_t(used.size()));
        for (std::size_t i = 0; i < used.size(); ++i) {
            mesh.vertices.row(std::int64_t(i)) = result.regularization.positions.row(used[i]);
            key[std::int64_t(i)] = double(keys[std::size_t(used[i])]);  // exact below 2^53
            local[std::size_t(used[i])] = -1;
        }
        mesh.vertex_scalars.emplace_back("key", key);
        std::string number = std::to_string(block);
        number.insert(0, number.size() < 6 ? 6 - number.size() : 0, '0');
        const std::string name = "block-" + number + ".ply";
        write_mesh((fs::path(folder) / name).string(), mesh);
        entry["vertices"] = used.size();
        entry["file"] = name;
        blocks.push_back(entry);
    }
    const VoxelGrid& g = result.grid;
    const nlohmann::json manifest = {
        {"input", result.input},
        {"grid", {{"dims", g.dims}, {"spacing", {g.spacing.x(), g.spacing.y(), g.spacing.z()}}, {"origin", {g.origin.x(), g.origin.y(), g.origin.z()}}}},
        {"keys", "vertex key = min over its umbrella of 4*(6*(i + nx*(j + ny*k)) + 2*axis + (sign > 0)) + corner; "
                 "a vertex shared by several fragments has the same key in each (include/dsreg/blocks.hpp)"},
        {"surfels", s.face_count()},
        {"vertices", s.vertex_count()},
        {"blocks", blocks}};
    const std::string text = manifest.dump(2) + "\n";
    write_file_atomically((fs::path(folder) / "manifest.json").string(), [&](std::ostream& out) { out << text; });
}

}  // namespace dsreg
