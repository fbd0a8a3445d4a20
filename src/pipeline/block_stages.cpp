// dsreg pipeline — what one block contributes (include/dsreg/block_pipeline.hpp).
#include <cmath>

#include "dsreg/block_pipeline.hpp"
#include "dsreg/error.hpp"
#include "pipeline_stages.hpp"
#include "stage_clock.hpp"

namespace dsreg {

namespace {

/// Voxels along each axis within `radius` of a face's voxel, plus the one the face centre is off by.
Index3 reach_in_voxels(double radius, const Eigen::Vector3d& spacing) {
    Index3 voxels{0, 0, 0};
    if (radius > 0)
        for (int a = 0; a < 3; ++a) voxels[a] = std::int64_t(std::ceil(radius / spacing[a])) + 1;
    return voxels;
}

/// Throws unless the options can run block by block.
void refuse_global_options(const PipelineOptions& o, const std::string& driver) {
    const RegularizationExtensions& e = o.extensions;
    const auto refuse = [&](bool given, const std::string& flag, const std::string& why) {
        if (given) throw Error(flag + " cannot be used with " + driver + ": " + why);
    };
    refuse(e.clamp, "--clamp", "the box-constrained solve couples the whole surface");
    const std::string local = "local weights are given for the whole surface or volume at once";
    refuse(!e.alpha_map.empty(), "--alpha-map", local);
    refuse(!e.beta_map.empty(), "--beta-map", local);
    refuse(!e.gamma_map.empty(), "--gamma-map", local);
    refuse(!e.alpha_file.empty(), "--alpha-file", local);
    refuse(!e.beta_file.empty(), "--beta-file", local);
    refuse(!e.gamma_file.empty(), "--gamma-file", local);
    // The adaptive field, the thin-part and noise weights and the shrink correction rest on
    // distance maps and averages that span the whole object: block-wise runs have a fixed radius
    // (normal_field_reach) and none of the corrections yet (block_wise_options).
    const std::string whole = "it is measured on the whole object (not block by block yet)";
    refuse(o.normals.max_radius.has_value(), "--ii-max-radius", whole);
    refuse(o.normals.extrapolation_threshold_deg.has_value(), "--ii-extrapolation-threshold", whole);
    refuse(o.normals.noisy_smoothing_steps.has_value(), "--ii-noise-smoothing", whole);
    refuse(e.alpha_reach && *e.alpha_reach > 0, "--alpha-reach", whole);
    refuse(e.alpha_reach_sheet.has_value(), "--alpha-reach-sheet", whole);
    refuse(e.shrink_correction && *e.shrink_correction > 0, "--shrink-correction", whole);
    refuse(e.shrink_local_steps.has_value(), "--shrink-local-steps", whole);
    refuse(e.shrink_wide_steps.has_value(), "--shrink-wide-steps", whole);
    refuse(e.shrink_wide_tolerance.has_value(), "--shrink-wide-tolerance", whole);
    refuse(e.noise_fairness && *e.noise_fairness > 0, "--noise-fairness", whole);
}

std::int64_t object_voxels_in(const BinaryVolume& volume, const VoxelBox& volume_box, const VoxelBox& box) {
    std::int64_t count = 0;
    for (std::int64_t k = box.lo[2]; k < box.hi[2]; ++k)
        for (std::int64_t j = box.lo[1]; j < box.hi[1]; ++j)
            for (std::int64_t i = box.lo[0]; i < box.hi[0]; ++i)
                count += volume.inside(i - volume_box.lo[0], j - volume_box.lo[1], k - volume_box.lo[2]);
    return count;
}

/// The terms of eq. (1) among some faces and vertices of a patch, as a mesh of their own: the
/// data term of its vertices, the alignment of its faces, and the fairness of the vertices whose
/// faces (all of them, in the patch) are there (a vertex missing part of its link would get a
/// fairness term that is not one of R's, pulling it towards the part that is there).
struct SubMesh {
    std::vector<std::int32_t> vertices;  ///< patch indices, increasing
    PointMatrix positions;
    FaceMatrix quads;
    PointMatrix normals;
    RegularizationWeights weights;
};

Eigen::VectorXd restricted(const Eigen::VectorXd& values, const std::vector<std::int32_t>& rows) {
    if (values.size() == 0) return values;
    Eigen::VectorXd out(std::int64_t(rows.size()));
    for (std::size_t q = 0; q < rows.size(); ++q) out[std::int64_t(q)] = values[rows[q]];
    return out;
}

/// The faces with `face_selected`, their vertices and the vertices with `vertex_selected`.
SubMesh internal_terms(const BlockStages& b, const std::vector<char>& face_selected, const std::vector<char>& vertex_selected) {
    const DigitalSurface& s = b.patch.surface;
    std::vector<char> used(vertex_selected);
    std::vector<char> whole_link(used.size(), 1);
    std::vector<std::int32_t> faces;
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        for (int k = 0; k < 4; ++k) {
            const std::size_t v = std::size_t(s.quads(f, k));
            if (face_selected[std::size_t(f)])
                used[v] = 1;
            else
                whole_link[v] = 0;
        }
        if (face_selected[std::size_t(f)]) faces.push_back(std::int32_t(f));
    }
    SubMesh m;
    std::vector<std::int32_t> index(used.size(), -1);
    for (std::size_t i = 0; i < used.size(); ++i)
        if (used[i]) index[i] = std::int32_t(m.vertices.size()), m.vertices.push_back(std::int32_t(i));
    m.positions.resize(std::int64_t(m.vertices.size()), 3);
    for (std::size_t i = 0; i < m.vertices.size(); ++i) m.positions.row(std::int64_t(i)) = s.vertices.row(m.vertices[i]);
    m.quads.resize(std::int64_t(faces.size()), 4);
    m.normals.resize(std::int64_t(faces.size()), 3);
    for (std::size_t q = 0; q < faces.size(); ++q) {
        m.normals.row(std::int64_t(q)) = b.field.normals.row(faces[q]);
        for (int k = 0; k < 4; ++k) m.quads(std::int64_t(q), k) = index[std::size_t(s.quads(faces[q], k))];
    }
    const RegularizationWeights& w = b.weights;
    m.weights = RegularizationWeights{w.alpha, w.beta, w.gamma, restricted(w.vertex_weights, m.vertices),
                                      restricted(w.face_weights, faces)};
    m.weights.vertex_alpha = restricted(w.vertex_alpha, m.vertices);
    m.weights.face_beta = restricted(w.face_beta, faces);
    Eigen::VectorXd gamma = w.vertex_gamma.size() ? restricted(w.vertex_gamma, m.vertices)
                                                  : Eigen::VectorXd::Ones(std::int64_t(m.vertices.size()));
    for (std::size_t i = 0; i < m.vertices.size(); ++i)
        if (!whole_link[std::size_t(m.vertices[i])]) gamma[std::int64_t(i)] = 0;
    m.weights.vertex_gamma = gamma;
    if (w.fairness_targets.rows() > 0) m.weights.fairness_targets = w.fairness_targets(m.vertices, Eigen::all);
    return m;
}

RegularizationSystem assemble(const SubMesh& m) {
    return assemble_regularization_system(m.positions, m.quads, vertex_links(m.quads, m.positions.rows()), m.normals, m.weights);
}

double stage_time(const StageClock& clock, const std::string& name) {
    double seconds = 0;
    for (const auto& [stage, time] : clock.stage_seconds())
        if (stage == name) seconds += time;
    return seconds;
}

}  // namespace

BlockPlan plan_block_run(const VolumeSource& source, const PipelineOptions& options, const std::string& driver) {
    check_pipeline_options(options, !source.shape.empty());
    refuse_global_options(options, driver);
    if (!source.max_memory.empty())
        throw Error("--max-memory cannot be used with " + driver +
                    ": its estimate is that of the whole-volume run (choose the block size instead)");
    if (source.is_multi_label())
        throw Error(std::string(source.labels.empty() ? "--multi-label" : "--labels") + " cannot be used with " + driver +
                    ": label maps are regularized as a whole (run dsreg regularize without --block-size)");
    BlockPlan plan;
    plan.header = probe_volume(source);
    plan.reach = normal_field_reach(options.normals, plan.header);
    plan.options = options;
    plan.options.normals = plan.reach.options;
    plan.options.extensions.alpha_reach = 0.0;
    plan.options.extensions.shrink_correction = 0;
    plan.options.extensions.noise_fairness = 0.0;
    if (source.raw_layout) plan.options.extensions.map_raw_layout = *source.raw_layout;
    const Eigen::Vector3d& spacing = plan.header.volume.grid.spacing;
    const Index3 surface = reach_in_voxels(plan.reach.surface_radius, spacing);
    plan.surface_margin = std::max({surface[0], surface[1], surface[2]});
    const Index3 volume = reach_in_voxels(plan.reach.volume_radius, spacing);
    for (int a = 0; a < 3; ++a)
        plan.read_margin[a] = std::max(kPatchVolumeMargin + plan.surface_margin, kPatchFaceMargin + volume[a]);
    return plan;
}

VoxelBox block_read_box(const BlockPlan& plan, const VoxelBox& rows) {
    return rows.grown(plan.read_margin).clipped(plan.header.volume.grid.dims);
}

BlockStages run_block_stages(const VolumeSource& source, const BlockPlan& plan, const VoxelBox& owned, const VoxelBox& rows,
                             BlockAssembly assembly) {
    const PipelineOptions& o = plan.options;
    BlockStages b;
    b.owned = owned;
    b.rows = rows;
    b.read = block_read_box(plan, rows);
    StageClock clock{ProgressCallback{}};
    clock.start("read");
    LoadedVolume loaded;
    loaded.volume = load_volume_box(source, plan.header, b.read);
    loaded.description = plan.header.description;
    loaded.shape = plan.header.shape;
    loaded.h = plan.header.h;
    b.owned_object_voxels = object_voxels_in(loaded.volume, b.read, owned);
    clock.start("surface");
    b.patch = extract_surface_patch(loaded.volume, b.read, plan.header.volume.grid, owned, rows, o.connectivity,
                                    plan.surface_margin);
    clock.finish();
    if (b.patch.face_count() > 0) {
        b.field = compute_normal_field(o.normals, loaded, b.patch.surface, clock);
        clock.start("assembly");
        b.weights = RegularizationWeights{o.alpha, o.beta, o.gamma, {}, {}};
        apply_regularization_extensions(o.extensions, b.patch.surface, b.field, ThinParts(), b.weights);
        const DigitalSurface& s = b.patch.surface;
        b.system = assembly == BlockAssembly::matrix_and_rhs
                       ? assemble_regularization_system(s.vertices, s.quads, vertex_links(s.quads, s.vertex_count()),
                                                        b.field.normals, b.weights)
                       : regularization_right_hand_side(s.vertices, VertexLinks{}, b.weights);  // binary: no fairness targets
        clock.finish();
    }
    b.read_seconds = stage_time(clock, "read");
    b.surface_seconds = stage_time(clock, "surface");
    b.normals_seconds = stage_time(clock, "normals");
    b.assembly_seconds = stage_time(clock, "assembly");
    return b;
}

SolveReport solve_patch_rows(const BlockStages& block, Eigen::VectorXd& x, const SolverOptions& solver) {
    const SurfacePatch& patch = block.patch;
    const Eigen::SparseMatrix<double>& R = block.system.matrix;
    const std::int64_t n = patch.vertex_count();
    // Unknowns: the scalar entries of the row vertices, in patch order (a monotone map, so that
    // columns of R_SS come out sorted).
    std::vector<std::int64_t> unknown(static_cast<std::size_t>(3 * n), -1);
    std::int64_t count = 0;
    for (std::int64_t i = 0; i < n; ++i)
        if (patch.vertex_row[std::size_t(i)])
            for (int d = 0; d < 3; ++d) unknown[std::size_t(3 * i + d)] = count++;
    // R is symmetric: column c is row c. R_SS by columns; b_S − R_SO x_O.
    Eigen::SparseMatrix<double> reduced(count, count);
    Eigen::VectorXd rhs(count), guess(count);
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(std::size_t(R.nonZeros()));
    for (std::int64_t c = 0; c < 3 * n; ++c) {
        const std::int64_t column = unknown[std::size_t(c)];
        if (column < 0) continue;
        double held = 0;
        for (Eigen::SparseMatrix<double>::InnerIterator it(R, Eigen::Index(c)); it; ++it) {
            const std::int64_t row = unknown[std::size_t(it.row())];
            if (row >= 0)
                entries.emplace_back(Eigen::Index(row), Eigen::Index(column), it.value());
            else
                held += it.value() * x[it.row()];
        }
        rhs[column] = block.system.rhs[c] - held;
        guess[column] = x[c];
    }
    if (count == 0) return SolveReport{};
    reduced.setFromTriplets(entries.begin(), entries.end());
    entries = {};
    SolverOptions options = solver;
    options.smallest_eigenvalue = smallest_eigenvalue_bound(block.weights, patch.vertex_row);
    const SolveReport report = solve_spd(reduced, rhs, guess, options);
    for (std::int64_t c = 0; c < 3 * n; ++c)
        if (unknown[std::size_t(c)] >= 0) x[c] = guess[unknown[std::size_t(c)]];
    return report;
}

SolveReport solve_patch_free(const BlockStages& block, Eigen::VectorXd& x, const SolverOptions& solver) {
    const SurfacePatch& patch = block.patch;
    std::vector<char> inside(std::size_t(patch.face_count()), 0);
    for (std::int64_t f = 0; f < patch.face_count(); ++f) {
        const Surfel& s = patch.surface.surfels[std::size_t(f)];  // in read-box coordinates
        inside[std::size_t(f)] =
            block.rows.contains(s.voxel[0] + block.read.lo[0], s.voxel[1] + block.read.lo[1], s.voxel[2] + block.read.lo[2]);
    }
    const SubMesh m = internal_terms(block, inside, std::vector<char>(std::size_t(patch.vertex_count()), 0));
    const RegularizationSystem system = assemble(m);
    Eigen::VectorXd guess(3 * std::int64_t(m.vertices.size()));
    for (std::size_t i = 0; i < m.vertices.size(); ++i) guess.segment<3>(3 * std::int64_t(i)) = x.segment<3>(3 * m.vertices[i]);
    SolverOptions options = solver;
    options.smallest_eigenvalue = smallest_eigenvalue_bound(m.weights, m.positions.rows());
    const SolveReport report = solve_spd(system.matrix, system.rhs, guess, options);
    for (std::size_t i = 0; i < m.vertices.size(); ++i) x.segment<3>(3 * m.vertices[i]) = guess.segment<3>(3 * std::int64_t(i));
    return report;
}

double owned_energy_norm_bound(const BlockStages& block, const Eigen::VectorXd& residual, const SolverOptions& solver) {
    const SurfacePatch& patch = block.patch;
    const DigitalSurface& s = patch.surface;
    std::vector<char> internal(std::size_t(s.face_count()), 0);
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        bool all_owned = true;
        for (int k = 0; k < 4; ++k) all_owned = all_owned && patch.vertex_owned[std::size_t(s.quads(f, k))];
        internal[std::size_t(f)] = all_owned;
    }
    const SubMesh m = internal_terms(block, internal, patch.vertex_owned);
    if (m.vertices.empty()) return 0;  // a block may own faces but none of their vertices
    const RegularizationSystem system = assemble(m);
    Eigen::VectorXd r(3 * std::int64_t(m.vertices.size()));
    for (std::size_t i = 0; i < m.vertices.size(); ++i) r.segment<3>(3 * std::int64_t(i)) = residual.segment<3>(3 * m.vertices[i]);
    // z ≈ M⁻¹ r; with s = r − M z: rᵀM⁻¹r = zᵀMz + 2 zᵀs + sᵀM⁻¹s ≤ zᵀMz + 2 zᵀs + ‖s‖²/λ_min(M).
    const double smallest = smallest_eigenvalue_bound(m.weights, m.positions.rows());
    SolverOptions options = solver;
    options.smallest_eigenvalue = smallest;
    Eigen::VectorXd z = Eigen::VectorXd::Zero(r.size());
    solve_spd(system.matrix, r, z, options);
    const Eigen::VectorXd Mz = system.matrix * z;
    const Eigen::VectorXd rest = r - Mz;
    return z.dot(Mz) + 2 * z.dot(rest) + rest.squaredNorm() / smallest;
}

}  // namespace dsreg
