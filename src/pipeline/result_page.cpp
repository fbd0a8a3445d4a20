// dsreg pipeline — the --html page of a run (result_page, include/dsreg/pipeline.hpp).
#include <string>
#include <vector>

#include "dsreg/pipeline.hpp"
#include "dsreg/text.hpp"
#include "pipeline_stages.hpp"

namespace dsreg {

namespace {

std::string triple(const Eigen::Vector3d& v, const char* pattern) {
    return format(pattern, v.x()) + " × " + format(pattern, v.y()) + " × " + format(pattern, v.z());
}

std::string dims_text(const VoxelGrid& grid) {
    return std::to_string(grid.dims[0]) + " × " + std::to_string(grid.dims[1]) + " × " + std::to_string(grid.dims[2]);
}

/// The run's summary, from input to times: what the report holds, in a few readable lines.
std::vector<SummaryLine> run_summary(const PipelineResult& r, const PipelineOptions& o) {
    const RegularizationResult& reg = r.regularization;
    std::vector<SummaryLine> lines = {
        {"input", r.input},
        {"grid", dims_text(r.grid) + " voxels of " + triple(r.grid.spacing, "%g")},
        {"object voxels", std::to_string(r.object_voxels)},
        {"surfels", std::to_string(r.surface.face_count())},
        {"vertices", std::to_string(r.surface.vertex_count())},
        {"components", std::to_string(r.surface.component_count)},
        {"normal field", r.field.description},
        {"α, β, γ", format("%g", o.alpha) + ", " + format("%g", o.beta) + ", " + format("%g", o.gamma)},
        {"solver", reg.solve.solver + ", residual " + format("%.1e", reg.solve.relative_residual)},
        {"energy", format("%.4g", reg.energy_before.total(r.weights)) + " → " +
                       format("%.4g", reg.energy_after.total(r.weights))},
    };
    if (!r.label_meshes.empty())
        lines.push_back({"labels", std::to_string(r.label_meshes.size()) + ", " + std::to_string(r.junctions.vertex_count) +
                                       " junction vertices"});
    if (r.faces_against_field > 0) lines.push_back({"faces folded against u", std::to_string(r.faces_against_field)});
    if (r.field.at)
        lines.push_back({"Ambrosio–Tortorelli", std::to_string(r.field.at->total_rounds()) + " rounds, " +
                                                    std::to_string((r.field.at->features.array() <
                                                                    o.normals.feature_threshold).count()) +
                                                    " feature vertices"});
    for (const auto& [stage, seconds] : r.stage_seconds) lines.push_back({stage, format("%.3f s", seconds)});
    lines.push_back({"total", format("%.2f s", total_seconds(r))});
    lines.push_back({"peak memory", human_bytes(double(peak_memory_bytes()))});
    return lines;
}

}  // namespace

ViewPage result_page(const PipelineResult& result, const PipelineOptions& options) {
    ViewPage page;
    page.title = "dsreg: " + result.input;
    page.summary = run_summary(result, options);
    page.feature_threshold = options.normals.feature_threshold;
    const bool unit_voxels = result.grid.spacing == Eigen::Vector3d::Ones();
    page.length_unit = unit_voxels ? "voxels" : "physical units";
    ViewLayer layer;
    layer.name = "regularized surface";
    layer.mesh = result_mesh(result, false);
    layer.digital = result_mesh(result, false, true);
    if (!result.label_meshes.empty()) {
        // The region behind a face (it bounds) is its inner label, the one in front its outer label.
        layer.face_labels.resize(result.surface.face_count(), 2);
        for (std::int64_t f = 0; f < result.surface.face_count(); ++f) {
            const FaceLabels& l = result.surface.face_labels[std::size_t(f)];
            layer.face_labels(f, 0) = static_cast<std::int32_t>(result.surface.label_values[l.inner]);
            layer.face_labels(f, 1) = static_cast<std::int32_t>(result.surface.label_values[l.outer]);
        }
    }
    page.layers.push_back(std::move(layer));
    return page;
}

}  // namespace dsreg
