// dsreg CLI — `dsreg regularize`: the flags of the pipeline (include/dsreg/pipeline.hpp), its
// stage lines and its summary line, shared with dsreg-mpi. Everything else happens in the library.
#include "regularize_command.hpp"

#include <unistd.h>

#include <cstdlib>
#include <iostream>
#include <memory>

#include "dsreg/error.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/progress_display.hpp"
#include "dsreg/regularization_metrics.hpp"
#include "dsreg/text.hpp"

namespace dsreg::cli {

namespace {

void add_volume_source_options(CLI::App& command, VolumeSource& o, CliFlags& flags) {
    command.add_option("--shape", o.shape,
                       "Implicit shape instead of a file: a named shape (sphere1 sphere9 ellipsoid cylinder torus "
                       "rcube goursat goursat-hole distel leopold diabolo heart crixxi) or a polynomial such as "
                       "\"x^2+y^2+z^2-25\" (F <= 0 inside)");
    command.add_option("--h", o.h, "Grid step for --shape, physical units (default: 1/64 of the shape's extent)");
    command.add_option("--box", o.box, "Half-size of the domain of a polynomial --shape")->capture_default_str();
    command.add_option("--min", o.min_value, "Object = voxels with value >= MIN (default: value > 0)");
    command.add_option("--max", o.max_value, "Object = voxels with value <= MAX");
    command.add_option("--label", o.label, "Object = voxels equal to N (a label of a label map; not with --min/--max)");
    command.add_option("--raw-dims", flags.raw_dims, "Dimensions X,Y,Z of a .raw volume")->expected(3)->delimiter(',');
    command.add_option("--raw-type", flags.raw_type, "Voxel type of a .raw volume: uint8 int8 uint16 int16 uint32 int32 "
                                                     "uint64 int64 float32 float64")
        ->capture_default_str();
    command.add_flag("--raw-big-endian", flags.raw_big_endian, "Values of the .raw volume are big-endian");
    command.add_option("--raw-header-bytes", flags.raw_header_bytes, "Bytes to skip at the start of the .raw volume");
    command.add_option("--spacing", flags.spacing, "Voxel size SX,SY,SZ in physical units (overrides the file's)")
        ->expected(3)
        ->delimiter(',');
    command.add_option("--max-voxels", o.max_voxels, "Refuse volumes with more voxels than this")->capture_default_str();
    command.add_flag("--multi-label", o.multi_label,
                     "The input is a label map: every non-zero value is a label, and every interface between two "
                     "labels (or a label and the background) is regularized at once, shared by both; writes -o with "
                     "every interface face once and OUT-<label>.EXT, the closed surface of each label "
                     "(docs/multi-label.md)");
    command.add_option("--labels", o.labels,
                       "With --multi-label (implied): keep these labels, e.g. 1,4,7; the other voxels join the background")
        ->delimiter(',');
    command.add_option("--max-memory", o.max_memory,
                       "Refuse runs whose estimated peak memory exceeds this, e.g. 4G, 512M (K/M/G/T: powers of 1024)");
}

void add_normal_field_options(CLI::App& cmd, NormalFieldOptions& o, PipelineOutputs& outputs, CliFlags& flags) {
    cmd.add_option("--normals", o.kind,
                       "Normal field: ii (integral invariants), trivial (voxel faces), ctrivial (trivial normals "
                       "averaged within --radius), exact (true normals of a --shape), or at (Ambrosio-Tortorelli "
                       "piecewise-smooth regularization of --at-input or --normals-file: keeps sharp features)")
        ->check(CLI::IsMember({"ii", "trivial", "ctrivial", "exact", "at"}));
    cmd.add_option("--radius", o.radius,
                   "A fixed radius for ii and ctrivial, physical units (default for ii: adaptive, see --ii-max-radius; "
                   "for ctrivial and --ii-extrapolate: 3·h^(1/3) for --shape, 3 voxels for files)");
    cmd.add_option("--ii-max-radius", o.max_radius,
                   "Largest radius of the adaptive integral invariants (the default field), physical units: each "
                   "surfel's radius follows the local reach of the object and of the background, from 2 voxels up to "
                   "this; extrapolated from 6 voxels up (docs/accuracy.md). Default 14 voxels");
    cmd.add_option("--ii-extrapolation-threshold", o.extrapolation_threshold_deg,
                   "The adaptive field's Richardson correction 2 (n(r/sqrt(2)) - n(r)) is shrunk by this many degrees "
                   "(soft threshold: a correction at the level of the digitization noise is no evidence of bias; "
                   "docs/accuracy.md, 'The extrapolation's threshold'). Default 0.75")
        ->check(CLI::NonNegativeNumber);
    cmd.add_option("--ii-noise-smoothing", o.noisy_smoothing_steps,
                   "Noisy thin parts: the adaptive field's faces of radius under 5 voxels (thin parts), where a share of at least 0.005 "
                   "of the faces within about 8 rings point against their surfel, get this many more steps of averaging "
                   "with their neighbours (docs/accuracy.md, 'Noise on thin parts'); 0 = off. Default 40");
    cmd.add_option("--ii-kernel", o.ii_kernel,
                   "Weights of the integral-invariant ball: biweight (1 - d^2/r^2)^2, smooth, more accurate "
                   "(docs/accuracy.md), or ball (uniform, the paper's integral invariants)")
        ->check(CLI::IsMember({"ball", "biweight"}))
        ->capture_default_str();
    cmd.add_flag("--ii-extrapolate", o.ii_extrapolate,
                 "Integral invariants at r and r/sqrt(2) combined as 2 n(r/sqrt(2)) - n(r): removes the bias that "
                 "grows like r^2 (far more accurate on smooth shapes whose features are much larger than r; "
                 "docs/accuracy.md). Default radius doubles");
    cmd.add_option("--normals-file", o.file,
                   "Read the normal field from this text file (lines 'i j k direction nx ny nz', see "
                   "docs/ambrosio-tortorelli.md); with --normals at, the field to regularize");
    cmd.add_option("--at-input", o.at_input, "Field that --normals at regularizes (default ii)")
        ->check(CLI::IsMember({"ii", "trivial", "ctrivial", "exact"}));
    flags.at_only = {
        cmd.add_option("--at-alpha", o.at.alpha, "AT attachment weight a (grid units)")->capture_default_str(),
        cmd.add_option("--at-lambda", o.at.lambda, "AT feature length cost lambda (grid units)")->capture_default_str(),
        cmd.add_option("--at-eps", flags.at_epsilon, "AT epsilon from EPS1 down to EPS2, in voxels (EPS1:EPS2)")
            ->capture_default_str(),
        cmd.add_option("--at-eps-ratio", o.at.epsilon_ratio, "AT: epsilon is divided by this between levels (> 1)")
            ->capture_default_str(),
        cmd.add_option("--features", outputs.features,
                       "Write the sharp edges found by --normals at (mesh edges with v < --feature-threshold at both "
                       "ends) as OBJ polylines"),
        cmd.add_option("--feature-threshold", o.feature_threshold, "v below which a vertex is on a feature")
            ->capture_default_str(),
    };
    CLI::Option* lift_margin = cmd.add_option("--field-lift-margin", o.lift_margin,
                   "Estimated normals u with u.n_s below this (n_s: the axis normal of the face's voxel side, "
                   "which the voxels make certain) are tilted to u.n_s = this: the faces that would fold "
                   "(docs/accuracy.md, 'Field lift'); not --normals exact nor a --normals-file field. Default 0.05")
        ->check(CLI::Range(0.0, 0.99));
    cmd.add_flag_callback("--no-field-lift", [&o] { o.lift_margin.reset(); }, "Use the estimated normals as they are")
        ->excludes(lift_margin);
    cmd.add_option("--export-normals", outputs.normals,
                   "Write the normal field used (after AT, if any) in the --normals-file format");
}


void add_regularization_extension_options(CLI::App& command, RegularizationExtensions& o) {
    command.add_flag("--clamp", o.clamp,
                     "Reversible mode: keep each vertex within --clamp-half-width voxels of its digital position on each "
                     "axis (exact box-constrained minimizer)");
    command.add_option("--clamp-tolerance", o.clamp_tolerance, "Relative KKT residual the clamped solve must reach")
        ->capture_default_str();
    command.add_option("--clamp-half-width", o.clamp_half_width,
                       "Box half-width in voxels (0.5 = the cube of the 8 voxel centres around a vertex; below 0.5 every "
                       "voxel centre stays strictly on its side)")
        ->capture_default_str();
    command.add_option("--alpha-reach", o.alpha_reach,
                       "Thin parts: the data term of a vertex whose local reach rho (physical units) is below R is "
                       "weighted (R/rho)^2, so that thin tubes and plates do not shrink (docs/accuracy.md); 0 = off. "
                       "Default 12 voxels");
    command.add_option("--alpha-reach-sheet", o.alpha_reach_sheet,
                       "Thin parts that are sheets (plates, shells, gaps between two walls) rather than tubes: their "
                       "data term is weighted (R/rho)^2 with this R instead, as a flat sheet does not shrink and a "
                       "strong weight only pins it to its staircase (docs/accuracy.md, 'Sheets and tubes'); the "
                       "--alpha-reach value weights sheets as tubes. Default 2 voxels");
    command.add_option("--shrink-correction", o.shrink_correction,
                       "Steps of averaging of the drift of the regularized surface along u, which is then removed "
                       "(the solve's result lies slightly inside the digital surface; docs/accuracy.md); 0 = off. "
                       "Default 40, off with --clamp");
    command.add_option("--shrink-local-steps", o.shrink_local_steps,
                       "On thin tubes (reach below a third of the --alpha-reach reference; not where the voxels are "
                       "noisy) the drift of --shrink-correction is averaged over this many steps instead, so that a "
                       "tube's convex side, which drifts in further, is corrected too (docs/accuracy.md, 'Local shrink "
                       "on thin tubes'); 0 = off. Default 10");
    command.add_option("--shrink-wide-steps", o.shrink_wide_steps,
                       "The drift of --shrink-correction is averaged over this many steps too, and the wide average "
                       "taken wherever the two differ by less than --shrink-wide-tolerance: it removes the staircase's "
                       "ripple that the narrow average leaves on smooth surfaces, and keeps a drift that varies "
                       "(docs/accuracy.md, 'A wide shrink average where the drift agrees'); 0 = off. Default 160");
    command.add_option("--shrink-wide-tolerance", o.shrink_wide_tolerance,
                       "Where the narrow and wide averages of the drift differ by more than this (voxels), the "
                       "difference beyond it is kept. Default 0.01");
    command.add_option("--noise-fairness", o.noise_fairness,
                       "Noisy voxels: the fairness of a vertex where a share rho of the faces around it have an estimated "
                       "normal pointing into the object is weighted 1 + G min(1, rho/0.02)^2 (docs/accuracy.md); 0 = off. "
                       "Default 12");
    command.add_option("--junction-turn-share", o.junction_turn_share,
                       "Label maps: each turn of a junction curve is asked to keep this share of its digital offset from "
                       "the chord of its two neighbours on the curve (a fairness target), so that the sliver between the "
                       "curve and its staircase does not fold (docs/multi-label.md, 'Turns of junction curves'); 0 = off "
                       "(the chord). Default 0.55")
        ->check(CLI::Range(0.0, 1.0));
    command.add_option("--junction-turn-weight", o.junction_turn_weight,
                       "Label maps: the least weight of those turns' fairness, relative to beta (the alignment of the "
                       "sheets meeting there, which the held turn works against). Default 0.3");
    command.add_option("--metric", o.metric, "Metrics W0, W2: identity (paper) or area (estimated face and dual vertex areas)")
        ->check(CLI::IsMember(metric_names()))
        ->capture_default_str();
    const char* map_help = " multipliers from a scalar volume on the input grid (mean of the 8 voxels around each vertex)";
    command.add_option("--alpha-map", o.alpha_map, std::string("Per-vertex alpha") + map_help);
    command.add_option("--beta-map", o.beta_map, std::string("Per-face beta") + map_help + "; faces: mean of their vertices");
    command.add_option("--gamma-map", o.gamma_map, std::string("Per-vertex gamma") + map_help);
    command.add_option("--alpha-file", o.alpha_file, "Per-vertex alpha multipliers: text file, one value per vertex in mesh order");
    command.add_option("--beta-file", o.beta_file, "Per-face beta multipliers: text file, one value per face in mesh order");
    command.add_option("--gamma-file", o.gamma_file, "Per-vertex gamma multipliers: text file, one value per vertex in mesh order");
}

/// --block-size N or X,Y,Z into the block options; the block flags need it.
void apply_block_flags(RegularizeCommand& c) {
    BlockOptions& blocks = c.options.blocks;
    const std::vector<std::int64_t>& size = c.flags.block_size;
    if (!size.empty()) {
        const std::size_t n = size.size();
        if (n == 2) throw Error("--block-size: give one size N or three X,Y,Z");
        for (int a = 0; a < 3; ++a) blocks.block_size[a] = size[n == 1 ? 0 : std::size_t(a)];
        for (std::int64_t s : blocks.block_size)
            if (s <= 0) throw Error("--block-size " + std::to_string(s) + ": block sizes must be positive");
    }
    if (!blocks.enabled() && blocks.halo) throw Error("--block-halo only applies with --block-size");
    if (!blocks.enabled() && blocks.schwarz_sweeps != 0) throw Error("--schwarz-sweeps only applies with --block-size");
    if (c.flags.coarse_spacing) {
        if (*c.flags.coarse_spacing < 0) throw Error("--coarse-spacing must be zero (off) or positive");
        if (!blocks.enabled()) throw Error("--coarse-spacing only applies with --block-size");
        blocks.coarse_spacing = *c.flags.coarse_spacing;
    }
    if (!blocks.enabled() && c.flags.coarse_space != "normals") throw Error("--coarse-space only applies with --block-size");
    blocks.coarse_along_normals = c.flags.coarse_space == "normals";
}

}  // namespace

void apply_flags(RegularizeCommand& c) {
    CliFlags& f = c.flags;
    RawVolumeLayout layout;
    layout.type = parse_raw_voxel_type(f.raw_type);
    layout.big_endian = f.raw_big_endian;
    layout.header_bytes = f.raw_header_bytes;
    c.options.extensions.map_raw_layout = layout;  // .raw weight maps are read like a .raw input
    if (!f.raw_dims.empty()) {
        layout.dims = {f.raw_dims[0], f.raw_dims[1], f.raw_dims[2]};
        c.source.raw_layout = layout;
    }
    if (!f.spacing.empty()) c.source.spacing = Eigen::Vector3d(f.spacing[0], f.spacing[1], f.spacing[2]);
    c.options.solver = parse_solver_kind(f.solver);
    c.outputs.space = parse_output_space(f.space);
    c.options.connectivity = f.connectivity == 6 ? Connectivity::Six : Connectivity::TwentySix;
    c.options.validity = f.no_check ? ValidityMode::Off : f.no_repair ? ValidityMode::Check : ValidityMode::Repair;
    c.options.keep_voxels = f.keep_voxels      ? VoxelKeeping::Always
                            : f.no_keep_voxels ? VoxelKeeping::Never
                                               : VoxelKeeping::Auto;
    NormalFieldOptions& normals = c.options.normals;
    const bool at = normals.kind == "at";
    for (const CLI::Option* option : f.at_only)
        if (option->count() > 0 && !at) throw Error(option->get_name() + " only applies to --normals at");
    if (at) parse_epsilon_range(f.at_epsilon, normals.at);
    apply_block_flags(c);
}

void apply_and_check_flags(RegularizeCommand& c) {
    apply_flags(c);
    check_pipeline_options(c.options, !c.source.shape.empty());
    check_multi_label_options(c.source, c.options);
    check_pipeline_outputs(c.outputs);
}

ProgressCallback stage_lines(bool shown, const std::string& prefix) {
    if (!shown) return {};
    ProgressDisplayOptions o;
    o.updates = false;  // the summary line of each stage only
    o.prefix = prefix;
    return progress_display(std::cerr, o);
}

bool stage_lines_shown(const CliFlags& flags) { return !flags.quiet && (flags.verbose || isatty(STDERR_FILENO)); }

void restart_with_passive_openmp_waiting(char** argv) {
    if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
    if (setenv("OMP_WAIT_POLICY", "passive", 1) != 0) return;
    execv("/proc/self/exe", argv);  // on failure, go on with the runtime's default policy
}

namespace {

/// On stderr: a live progress line on a terminal (or, with --progress, always: plain lines when
/// stderr is not a terminal), and the stage lines (stage_lines_shown).
ProgressCallback stderr_progress(const CliFlags& flags) {
    const bool terminal = isatty(STDERR_FILENO);
    ProgressDisplayOptions o;
    o.live = terminal;
    o.updates = flags.progress || (terminal && !flags.quiet);
    o.stage_summaries = stage_lines_shown(flags);
    if (!terminal) o.interval_seconds = 1.0;
    if (!o.updates && !o.stage_summaries) return {};
    return progress_display(std::cerr, o);
}

void run(RegularizeCommand& c) {
    apply_and_check_flags(c);
    if (!c.outputs.fragments.empty() && !c.options.blocks.enabled())
        throw Error("--fragments needs a block-wise run: give --block-size (or run dsreg-mpi)");
    const ProgressCallback progress = stderr_progress(c.flags);
    PipelineResult result = run_pipeline(c.source, c.options, progress);
    write_pipeline_outputs(result, c.options, c.outputs, c.source, progress);
    if (c.flags.quiet) return;
    for (const std::string& warning : result.warnings) std::cerr << "dsreg: warning: " << c.source.input_path << ": " << warning << '\n';
    std::cerr << "dsreg: " << summary_line(result, c.options) << " -> " << c.outputs.mesh
              << (result.file.world_geometry ? " (" + output_space_name(c.outputs.space) + ")" : "") << '\n';
}

}  // namespace

void add_pipeline_flags(CLI::App& command, RegularizeCommand& c) {
    add_volume_source_options(command, c.source, c.flags);
    command.add_option("--space", c.flags.space,
                       "Coordinates of the output meshes: lps (world, as ITK, DICOM and 3D Slicer), ras (world, as "
                       "nibabel, FreeSurfer, FSL), voxel (voxel indices, voxel centres at integers)")
        ->check(CLI::IsMember({"lps", "ras", "voxel"}, CLI::ignore_case))
        ->capture_default_str();
    command.add_option("--connectivity", c.flags.connectivity,
                       "Object connectivity where voxels touch by an edge: 6 keeps them apart, 26 joins them")
        ->check(CLI::IsMember({6, 26}))
        ->capture_default_str();
    add_normal_field_options(command, c.options.normals, c.outputs, c.flags);
    add_regularization_extension_options(command, c.options.extensions);
    command.add_option("--alpha", c.options.alpha, "Weight of data attachment (> 0)")->capture_default_str();
    command.add_option("--beta", c.options.beta, "Weight of normal alignment (>= 0)")->capture_default_str();
    command.add_option("--gamma", c.options.gamma, "Weight of fairness (>= 0)")->capture_default_str();
    command.add_option("--solver", c.flags.solver,
                       "Linear solver: auto (cholmod for small systems and tiny alpha, else amg), cholmod (sparse "
                       "Cholesky), amg (CG preconditioned by smoothed aggregation multigrid) or cg (block-Jacobi CG); "
                       "iterative solvers stop once their error bound is below --max-error")
        ->check(CLI::IsMember(solver_names()))
        ->capture_default_str();
    command.add_option("--max-error", c.options.max_error_voxels,
                       "Iterative solvers stop once their provable bound on the distance to the exact solution is "
                       "below this, in voxels")
        ->capture_default_str();
    command.add_flag("--no-repair", c.flags.no_repair,
                     "Keep the mesh as solved: self-intersections and faces folded against u are counted and reported "
                     "but not repaired (docs/validity.md)");
    command.add_flag("--no-check", c.flags.no_check, "Do not even count them (implies --no-repair)");
    CLI::Option* keep_voxels =
        command.add_flag("--keep-voxels", c.flags.keep_voxels,
                         "Put back every voxel centre the solved mesh has on the wrong side, however few (except where "
                         "the voxels are noisy), bounding the vertices around it along their faces' axes; by default "
                         "they are put back only when the object voxels left outside are at least 1 % of the "
                         "object's (docs/validity.md)");
    command.add_flag("--no-keep-voxels", c.flags.no_keep_voxels,
                     "Leave the voxel centres as the solve puts them, and do not count them")
        ->excludes(keep_voxels);
    command.add_flag("--triangulate", c.outputs.triangulate, "Split each quad along its shorter diagonal");
    command.add_option("--input-mesh", c.outputs.input_mesh, "Also write the unregularized digital surface to this file");
    command.add_option("--report", c.outputs.report, "Write counts, timings, energies and parameters as JSON");
    command.add_option("--html", c.outputs.html,
                       "Write a self-contained HTML page showing the result in 3D: the surface, the digital surface, "
                       "colours by deviation from u, displacement, feature map; the run's summary (docs/viewer.md)");
}

void add_block_flags(CLI::App& command, RegularizeCommand& c) {
    command.add_option("--block-size", c.flags.block_size,
                       "Block-wise streaming: read and solve the volume in blocks of N (or X,Y,Z) voxels, each with a "
                       "halo, and weld them into one mesh (memory of one block; docs/scaling.md)")
        ->delimiter(',')
        ->expected(1, 3);
    command.add_option("--block-halo", c.options.blocks.halo,
                       "Halo of each block, voxels (default: 2 sqrt(beta/alpha) + 2, from --alpha and --beta)");
    command.add_option("--schwarz-sweeps", c.options.blocks.schwarz_sweeps,
                       "Overlapping Schwarz sweeps after the first block-wise pass: each brings the mesh closer to the "
                       "whole-volume solve")
        ->capture_default_str();
    command.add_option("--coarse-spacing", c.flags.coarse_spacing,
                       "Two-level correction of block-wise runs: after the first pass and after each Schwarz sweep, "
                       "the Galerkin correction on a lattice of nodes this many voxels apart (trilinear; 0: off; "
                       "default " + std::to_string(BlockOptions().coarse_spacing) + ")");
    command.add_option("--coarse-space", c.flags.coarse_space,
                       "The coarse correction's displacements: along the normals (one unknown per node) or in every "
                       "direction (xyz: three; lower energy, but they slide vertices along the surface)")
        ->check(CLI::IsMember({"normals", "xyz"}))
        ->capture_default_str();
    command.add_option("--fragments", c.outputs.fragments,
                       "Block-wise runs: also write one PLY mesh per block (vertex property 'key': global vertex id) "
                       "and manifest.json into this folder");
}

void add_regularize_flags(CLI::App& command, RegularizeCommand& c) {
    command.add_option("input", c.source.input_path,
                       "Volume file: .nii .nii.gz .hdr/.img .nrrd .nhdr .mha .mhd .tif .h5 .vtk .dcm .npy .vol "
                       ".longvol .pgm3d .raw, or a folder holding a DICOM series");
    command.add_option("-o,--output", c.outputs.mesh,
                       "Output mesh: .obj .off .ply .vtk .vtp (quads) or .stl (triangles); .vtk and .vtp are 3D "
                       "Slicer's model formats")
        ->required();
    add_pipeline_flags(command, c);
    add_block_flags(command, c);
    command.add_flag("-q,--quiet", c.flags.quiet, "Print nothing but errors");
    command.add_flag("-v,--verbose", c.flags.verbose, "Print each stage as it finishes");
}

void add_regularize_command(CLI::App& app) {
    auto c = std::make_shared<RegularizeCommand>();
    CLI::App* cmd = app.add_subcommand("regularize", "Regularize the digital surface of a volume into a smooth quad mesh");
    add_regularize_flags(*cmd, *c);
    cmd->add_flag("--progress", c->flags.progress,
                  "Show progress on stderr even when it is not a terminal (one line per second; on a terminal a live "
                  "line is shown anyway, unless --quiet)");
    cmd->callback([c] { run(*c); });
}

}  // namespace dsreg::cli
