// dsreg — the whole pipeline in one call: volume → digital surface → normal field → regularized
// vertices → mesh files and report.
//
// This is the one implementation of what `dsreg regularize` does; the command-line tool, the
// Python module and the MPI driver are thin shells over it (they fill the option structs below
// and print or return the result). Options mirror the command-line flags: the field `ii_kernel`
// is the flag `--ii-kernel`, and error messages name the flags (`--radius must be positive`), so
// every front end reports the same problem in the same words.
//
// Units: every length (h, box, radius, positions) is in the volume's physical units (see
// volume.hpp); the pipeline works in the grid frame of volume.hpp (origin + spacing ⊙ index), and
// the mesh files are written in PipelineOutputs::space (world_space.hpp): LPS by default, which
// for the DGtal formats and shapes (identity direction) is the grid frame itself. A caller's array
// is placed by a voxel-to-world affine (grid_placement.hpp) into the same VoxelGrid geometry as a
// medical file's.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dsreg/adaptive_normals.hpp"
#include "dsreg/ambrosio_tortorelli.hpp"
#include "dsreg/blocks.hpp"
#include "dsreg/digital_surface.hpp"
#include "dsreg/html_view.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/label_evaluation.hpp"
#include "dsreg/label_surface.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/progress.hpp"
#include "dsreg/regularization.hpp"
#include "dsreg/solvers.hpp"
#include "dsreg/validity_repair.hpp"
#include "dsreg/volume.hpp"
#include "dsreg/volume_io.hpp"
#include "dsreg/voxel_array.hpp"
#include "dsreg/world_space.hpp"

namespace dsreg {

// ---------------------------------------------------------------------------------------------
// Stage 1: where the binary volume comes from.

/// A volume file, an implicit shape or a caller's array, and which voxels form the object.
struct VolumeSource {
    std::string input_path;   ///< a volume file (any format read_volume accepts), or
    std::string shape;        ///< a named shape or a polynomial in x, y, z (F ≤ 0 inside), or
    std::optional<VoxelArray> array;  ///< values in the caller's memory (the Python module's numpy arrays)
    /// Of an array: the voxel-to-world affine into `affine_space` (grid_placement.hpp); or
    /// `spacing` and `origin`.
    std::optional<Eigen::Matrix4d> affine;
    OutputSpace affine_space = OutputSpace::Lps;  ///< lps or ras (nibabel's img.affine)
    std::optional<Eigen::Vector3d> origin;       ///< of an array: centre of voxel (0,0,0); default 0
    std::optional<double> h;  ///< grid step of --shape; unset = default_grid_step
    double box = 10;          ///< half-size of the domain of a polynomial shape
    std::optional<double> min_value, max_value;  ///< object = MIN ≤ value ≤ MAX (default value > 0)
    std::optional<double> label;                 ///< --label N: object = voxels equal to N (not with min/max)
    std::optional<RawVolumeLayout> raw_layout;   ///< layout of a .raw file (--raw-dims, --raw-type, …)
    std::optional<Eigen::Vector3d> spacing;      ///< overrides the file's voxel size; an array's (default 1)
    std::int64_t max_voxels = std::int64_t(1) << 34;
    std::string max_memory;  ///< --max-memory as given ("4G"); empty = no limit
    /// --multi-label: the input is a label map, every non-zero value a label (a --shape is the
    /// label map {0, 1}), and the run regularizes every interface at once (docs/multi-label.md).
    bool multi_label = false;
    /// --labels: the labels kept (values); the other voxels join the background. Implies multi_label.
    std::vector<std::int64_t> labels;

    bool is_multi_label() const { return multi_label || !labels.empty(); }
};

/// A volume ready for the pipeline, with what the report says of it.
struct LoadedVolume {
    BinaryVolume volume;  ///< the object; for a label map only its grid (the mask is empty)
    std::optional<LabelVolume> labels;   ///< set for --multi-label: the label map
    std::string description;             ///< e.g. "bunny.vol" or "goursat at h=0.25"
    std::optional<ImplicitShape> shape;  ///< set for --shape inputs
    double h = 1;                        ///< grid step (largest spacing for files and arrays)
    VolumeFileInfo file;                 ///< format, value type and notes of a file input (format "array" for arrays)
    std::vector<std::string> warnings;   ///< e.g. an object taking most of the volume

    /// The voxels' labels: the label map's, or the object's (label 1).
    VoxelLabels voxel_labels() const { return labels ? VoxelLabels(*labels) : VoxelLabels(volume); }
};

/// Reads, digitizes or thresholds the volume. Honours max_voxels and max_memory before reading
/// any payload. Throws dsreg::Error on any problem, including an empty object (naming the
/// values the input has); dsreg::FileError when a file cannot be opened. When the object of a
/// file or array takes more than kMostOfTheVolume of its voxels (lobster.vol above 0: the
/// scanner's cylinder), adds a warning (for a file, with the value histogram's main modes).
LoadedVolume load_volume(const VolumeSource& source);

/// The fraction of the voxels above which the object is probably not the intended one.
constexpr double kMostOfTheVolume = 0.5;

/// What the pipeline knows of a volume before reading its voxels, for block-wise runs: the
/// LoadedVolume that load_volume would return, with an empty mask (grid with its world geometry,
/// file info, description, shape, h set), from the file's header alone or the shape's digitization grid (arrays are refused). --max-memory is not
/// applied (block-wise runs never hold the whole mask). Throws dsreg::Error as load_volume does.
LoadedVolume probe_volume(const VolumeSource& source);

/// The voxels of `box` of the volume that `header` (from probe_volume) describes, read by
/// offsets where the format allows (read_volume_box) or digitized over the box alone
/// (digitize_box): grid with the header's spacing, dims = box.size(), origin = the centre of
/// the box's first voxel.
BinaryVolume load_volume_box(const VolumeSource& source, const LoadedVolume& header, const VoxelBox& box);

/// The error for an object without any voxel: names the input and the value range used (and,
/// for a file whose values can be read within the limits, the range its values span).
Error empty_object_error(const VolumeSource& source, bool read_value_range);

/// The values of the volume file of `source` (not thresholded; volume_io.hpp's
/// read_volume_values) with the same limits, raw layout and --spacing as load_volume.
ScalarVolume load_volume_values(const VolumeSource& source, VolumeFileInfo* info = nullptr);

/// Parses a memory size: a number of bytes with an optional suffix K, M, G or T (powers of 1024,
/// optionally followed by "iB" or "B", any case), e.g. "4G", "512MiB", "1.5g", "1000000".
/// Throws dsreg::Error naming `option` unless it is a positive finite size below 2^63 bytes.
std::uint64_t parse_memory_size(const std::string& option, const std::string& text);

/// The number of surfels of the object of `volume` (6-neighbour object/background voxel faces,
/// the border counting as background), counted without building the surface: one pass over
/// the voxels, no allocation.
std::int64_t count_surfels(const BinaryVolume& volume);
/// The faces of a label map's complex (every two 6-neighbours of different labels, once).
std::int64_t count_surfels(const LabelVolume& volume);

/// Estimated peak memory (bytes) of the pipeline on `voxels` voxels whose object has `surfels`
/// surfels: a fixed 16 MiB, 1 byte per voxel (the mask), 3300 bytes per surfel (the surface, its
/// normals, the sparse system and solver vectors) and, when a sparse Cholesky factorization may
/// run (cholmod, auto), 640·m·log2(m) bytes for the factor (about 64·m·log2(m) nonzeros of ~10
/// bytes). Fitted on goursat h = 0.5 … 0.125 and bunny-128 (measured peaks 105 MiB … 1.86 GiB),
/// it overestimates by 10–30%. Local weight maps (4 bytes per voxel each) and Ambrosio–Tortorelli
/// normals are not counted.
/// A label map costs 4 bytes per voxel instead of 1 (`bytes_per_voxel`).
double estimate_run_memory(std::int64_t voxels, std::int64_t surfels, bool factorization, int bytes_per_voxel = 1);

/// Throws dsreg::Error if `source.max_memory` is set and the estimate above exceeds it. The
/// message gives the estimate, the counts it is made of, and what to change.
void check_run_memory(const VolumeSource& source, std::int64_t voxels, std::int64_t surfels, bool factorization);

/// The automatic grid step of a shape: 1/64 of the largest extent of its box.
double default_grid_step(const ImplicitShape& shape);

// ---------------------------------------------------------------------------------------------
// Stage 3: the normal field.

/// --ii-noise-smoothing's default, chosen on the accuracy suite (docs/accuracy.md, "Noise on thin parts").
constexpr int kDefaultNoisySmoothingSteps = 40;

struct NormalFieldOptions {
    std::string kind;  ///< --normals: ii trivial ctrivial exact at; empty: ii (or the field of --normals-file)
    std::optional<std::string> at_input;  ///< --at-input: the field g that AT regularizes (default ii)
    std::optional<double> radius;         ///< --radius (physical units): a fixed radius; unset = adaptive
    std::optional<double> max_radius;     ///< --ii-max-radius (physical units) of the adaptive field
    /// --ii-extrapolation-threshold (degrees): the adaptive field's Richardson correction is shrunk
    /// by this (AdaptiveNormalOptions::extrapolation_threshold_deg); unset = that default, 0.75°.
    std::optional<double> extrapolation_threshold_deg;
    /// --ii-noise-smoothing: the adaptive field's extra steps of averaging on noisy thin parts
    /// (AdaptiveNormalOptions::noisy_smoothing_steps); unset = kDefaultNoisySmoothingSteps, 0 = off.
    std::optional<int> noisy_smoothing_steps;
    std::string ii_kernel = "biweight";   ///< --ii-kernel: ball or biweight
    bool ii_extrapolate = false;          ///< --ii-extrapolate: 2·n(r/√2) − n(r)
    std::string file;                     ///< --normals-file: g (with --normals at) or the field itself
    AmbrosioTortorelliParameters at;      ///< --at-alpha, --at-lambda, --at-eps, --at-eps-ratio
    double feature_threshold = 0.5;       ///< --feature-threshold: v below it marks a feature vertex
    /// --field-lift-margin / --no-field-lift: estimated fields (not --normals exact or a normals
    /// file) are lifted into the surfels' half-spaces, u·n_s ≥ this (lift_into_surfel_half_spaces,
    /// normals.hpp); unset = no lift. 0.05 chosen on the accuracy suite (docs/accuracy.md).
    std::optional<double> lift_margin = 0.05;
};

/// "2:0.25" → ε from 2 down to 0.25; "0.5" → 0.5 throughout (the --at-eps syntax). Throws
/// dsreg::Error naming --at-eps.
void parse_epsilon_range(const std::string& text, AmbrosioTortorelliParameters& at);

/// Checks the options against each other and their values (before any long computation).
/// Throws dsreg::Error naming the flag.
void check_normal_field_options(const NormalFieldOptions& options, bool input_is_shape);

/// The default field, `--normals ii` without --radius or --ii-extrapolate, is the adaptive one
/// (adaptive_normals.hpp) with these radii (physical units): the largest 14 voxels (--ii-max-radius),
/// the smallest 2 voxels (of the smallest spacing), 1.5 times the reach, extrapolated from 6 voxels up, 4 smoothing steps
/// below 5 voxels; voxel = the largest spacing.
AdaptiveNormalOptions default_adaptive_options(const NormalFieldOptions& options, const LoadedVolume& loaded);

/// How far from a face the normal field of these options looks, for block-wise runs: the field
/// must be the same in every block, so the options come back with the radius the whole-volume
/// run would use filled in.
struct NormalFieldReach {
    NormalFieldOptions options;  ///< with `radius` set for ii and ctrivial
    double volume_radius = 0;    ///< the ball of voxels each face reads (ii), physical units
    double surface_radius = 0;   ///< the ball of surfels each face reads (ctrivial), physical units
};

/// Throws dsreg::Error for fields that need the whole surface at once (--normals at: its
/// Ambrosio–Tortorelli solve is global; --normals-file: the file lists the whole surface).
NormalFieldReach normal_field_reach(const NormalFieldOptions& options, const LoadedVolume& header);

/// The integral-invariant (or convolved trivial) radius used when --radius is not given (and the
/// field is not the adaptive one: --ii-extrapolate, --normals ctrivial): for a
/// shape the multigrid-convergent 3·h^(1/3) (DESIGN.md), at most 1/8 of the largest side of its
/// box (3·h^(1/3) suits shapes about 10 across; on smaller ones it would make a ball as wide as the
/// shape); for a file 3 voxels, or 5 voxels for ii with the biweight kernel (its weights fade
/// towards the sphere, so it needs a larger support for as little noise: docs/accuracy.md). Twice
/// that with --ii-extrapolate, whose extrapolation removes the bias that grows with r.
double default_field_radius(const NormalFieldOptions& options, const std::string& kind, const LoadedVolume& loaded);

struct NormalField {
    PointMatrix normals;                         ///< the field u the regularization uses
    std::string description;                     ///< e.g. "integral invariants (biweight kernel), r = 3"
    std::string input;                           ///< ii, trivial, ctrivial, exact or file (g for AT)
    std::optional<double> radius;                ///< radius used, if any
    std::optional<std::string> ii_kernel;        ///< kernel of the integral invariants, if used
    bool ii_extrapolated = false;                ///< Richardson-extrapolated integral invariants
    std::optional<AdaptiveNormalField> adaptive;  ///< set for the adaptive field (radii, reach)
    std::optional<AmbrosioTortorelliResult> at;  ///< set for --normals at
    /// Label maps: faces near a junction given the convolved trivial normals of their own
    /// interface (use_interface_normals_near_junctions, normals.hpp).
    std::int64_t interface_normal_faces = 0;
    /// Faces whose estimate was lifted into their surfel's half-space (NormalFieldOptions::lift_margin).
    std::int64_t lifted_faces = 0;
    /// Faces whose estimate pointed into the object before the lift (faces_against_their_surfels,
    /// normals.hpp): the noise measure of the fairness multipliers; empty for fields not lifted.
    std::vector<std::int32_t> faces_against_surfels;
};

// ---------------------------------------------------------------------------------------------
// Stage 4: the regularization beyond the paper's global weights.

/// --clamp, --metric and local weights (regularization_metrics.hpp, local_weights.hpp,
/// clamped_regularization.hpp).
struct RegularizationExtensions {
    bool clamp = false;               ///< keep each vertex in its box |p̂ − p| ≤ half-width · spacing per axis
    double clamp_tolerance = 1e-10;   ///< relative KKT residual the clamped solve must reach
    double clamp_half_width = 0.499;  ///< box half-width in voxels (< 0.5: docs/clamped.md)
    std::string metric = "identity";  ///< W0, W2: identity or area
    /// --alpha-reach: the data term is weighted max(1, (R/ρ)²) at vertices of reach ρ below R
    /// (thin_part_alpha, local_weights.hpp); physical units; unset = 12 voxels (the largest
    /// spacing); 0 = off. Multiplies --alpha-map / --alpha-file when both are given.
    std::optional<double> alpha_reach;
    /// --alpha-reach-sheet: the reference reach R_sheet of the thin parts that are sheets rather than
    /// tubes (thin_part_sheetness, thin_part_shape.hpp): their data term is weighted max(1,
    /// (R_sheet/ρ)²) instead; physical units; unset = 2 voxels (the largest spacing); equal to
    /// the --alpha-reach reference: every thin part weighted as a tube (and the sheetness not measured).
    std::optional<double> alpha_reach_sheet;
    /// --shrink-correction: averaging steps of correct_shrink (shrink_correction.hpp) applied to
    /// the solve's result; unset = 40 (off with --clamp, whose boxes it could leave); 0 = off.
    std::optional<int> shrink_correction;
    /// --shrink-local-steps: on thin tubes (thin-part multiplier above 9, i.e. reach below a third
    /// of the --alpha-reach reference; not where the noise fairness is raised) the drift is averaged
    /// over this many steps instead (correct_shrink's local_share); unset = 10; 0 = off.
    std::optional<int> shrink_local_steps;
    /// --shrink-wide-steps: the wide average of the drift, taken where it agrees with the
    /// --shrink-correction one within --shrink-wide-tolerance (ShrinkAveraging,
    /// shrink_correction.hpp); unset = 160; at most --shrink-correction: off.
    std::optional<int> shrink_wide_steps;
    /// --shrink-wide-tolerance: τ of the wide average, in voxels (of the smallest spacing); unset = 0.01.
    std::optional<double> shrink_wide_tolerance;
    /// --noise-fairness: gain G of the fairness multipliers 1 + G min(1, ρ/0.02)² where a share ρ
    /// of the faces around a vertex point against their surfel (noise_fairness_gamma,
    /// local_weights.hpp); unset = 12; 0 = off. Multiplies --gamma-map / --gamma-file.
    std::optional<double> noise_fairness;
    /// --junction-turn-share: on a label map, the share of its digital offset from the chord j₁j₃
    /// that each turn j₂ of a junction curve is asked to keep, through a fairness target
    /// (junction_turn_targets, label_surface.hpp; docs/multi-label.md): it keeps the turn's corner
    /// triangle from folding; unset = 0.55; 0 = off (the fairness straightens the curve to its chords).
    std::optional<double> junction_turn_share;
    /// --junction-turn-weight: the least weight of those turns' fairness, relative to β (their
    /// γ_i is raised to at least this × β/γ); unset = 0.3.
    std::optional<double> junction_turn_weight;
    std::string alpha_map, beta_map, gamma_map;     ///< scalar volumes on the input grid
    std::string alpha_file, beta_file, gamma_file;  ///< text files, one value per vertex (face for beta)
    RawVolumeLayout map_raw_layout;  ///< value type, byte order and header of .raw maps (dims: the input's)
    std::int64_t max_voxels = std::int64_t(1) << 34;  ///< limit for the maps
};

/// Checks what can be checked before any work. Throws dsreg::Error naming the flag.
void check_regularization_extensions(const RegularizationExtensions& options);

// ---------------------------------------------------------------------------------------------
// The whole run.

/// Block-wise streaming (block_pipeline.hpp): the volume is read and solved block by block, each
/// with a halo, and the blocks are welded into one mesh.
struct BlockOptions {
    Index3 block_size{0, 0, 0};        ///< --block-size (voxels); 0: the whole volume at once
    std::optional<std::int64_t> halo;  ///< --block-halo (voxels); unset: default_block_halo
    int schwarz_sweeps = 0;            ///< --schwarz-sweeps: overlapping Schwarz sweeps after the first pass
    /// --coarse-spacing (voxels; 0: off): the two-level correction on a lattice of nodes this far
    /// apart after the first pass and after each sweep (block_pipeline.hpp; 8: measured, docs/scaling.md)
    std::int64_t coarse_spacing = 8;
    /// --coarse-space: the coarse displacements move each vertex along the field u of its key
    /// surfel (one unknown per node; the default) or in every direction (xyz: three per node)
    bool coarse_along_normals = true;

    bool enabled() const { return block_size[0] > 0; }
};

/// What happens to the solved mesh (mesh_validity.hpp, validity_repair.hpp, docs/validity.md).
enum class ValidityMode {
    Repair,  ///< checked for self-intersections and faces folded against u, repaired until valid (default)
    Check,   ///< --no-repair: checked and reported, left as solved
    Off,     ///< --no-check: neither
};

/// The voxel centres the solved mesh puts on the wrong side (an object voxel's centre outside, a
/// background voxel's inside; docs/validity.md, "Voxel centres on their side"). Binary volumes
/// read whole only (not label maps, not block-wise runs); --clamp keeps them all anyway.
enum class VoxelKeeping {
    /// Counted and reported; put back (except where noisy) when the object voxels left outside
    /// are at least kVoxelPutBackShare of the object's (default): a mesh that lost that much of
    /// the segmentation is pulled back to it, one that did not keeps its smooth fit.
    Auto,
    Always,  ///< --keep-voxels: put back whenever there is one, except where the voxels are noisy
    Never,   ///< --no-keep-voxels: not even counted
};

/// VoxelKeeping::Auto's threshold, 1 % of the object voxels: below it, putting the centres back
/// costs the smooth shapes' accuracy (leopold h = 0.25 falls behind the Slicer pipeline) and
/// time; above it (bunny-64.vol, Al.100.vol) the mesh misses the voxels the issue-12 target
/// counts (docs/accuracy.md, "Voxel centres put back").
constexpr double kVoxelPutBackShare = 0.01;

struct PipelineOptions {
    Connectivity connectivity = Connectivity::TwentySix;  ///< --connectivity 6|26
    NormalFieldOptions normals;
    /// --alpha --beta --gamma (eq. 1). α = 3e-3 and γ = 3e-2, not the paper's 1e-3 and 1e-2:
    /// chosen on the accuracy suite (docs/accuracy.md, "The weights α and γ": 23 of 34 cases met
    /// against 19).
    double alpha = 3e-3, beta = 1.0, gamma = 3e-2;
    SolverKind solver = SolverKind::Auto;           ///< --solver
    /// --max-error: iterative solvers stop once their error bound is below this, in voxels
    /// (the smallest voxel side).
    double max_error_voxels = kDefaultMaxErrorVoxels;
    RegularizationExtensions extensions;
    BlockOptions blocks;
    ValidityMode validity = ValidityMode::Repair;   ///< --no-repair, --no-check
    /// --keep-voxels, --no-keep-voxels: whether the repair also puts back the voxel centres the
    /// solved mesh has on the wrong side (ValidityRepairOptions::voxels).
    VoxelKeeping keep_voxels = VoxelKeeping::Auto;
};

/// Checks every option of a run before any long computation. Throws dsreg::Error naming the flag.
void check_pipeline_options(const PipelineOptions& options, bool input_is_shape);

/// With --multi-label: what does not combine with it (--min/--max, --clamp, normal fields other
/// than ii, trivial or a file). Throws dsreg::Error naming the flags.
void check_multi_label_options(const VolumeSource& source, const PipelineOptions& options);

struct PipelineResult {
    std::string input;  ///< description of the input volume
    VoxelGrid grid;
    VolumeFileInfo file;                ///< format, value type, notes of a file input
    std::vector<std::string> warnings;  ///< from load_volume
    std::int64_t object_voxels = 0;
    DigitalSurface surface;
    NormalField field;
    RegularizationWeights weights;  ///< as used (metric and local multipliers filled in)
    RegularizationResult regularization;
    /// Faces of the final mesh whose mean normal points against u (count_faces_against_field).
    std::int64_t faces_against_field = 0;
    /// Faces of a thin part measured as a sheet (sheetness ≥ 1/2, thin_part_shape.hpp).
    std::int64_t sheet_faces = 0;
    /// The check and repair of the solved mesh (stage "validity"), unless ValidityMode::Off. With a
    /// repair, regularization.positions and field.normals are the repaired ones (the solve's
    /// energies stay in regularization; the repair's are here).
    std::optional<ValidityRepairReport> validity;
    nlohmann::json extension_report;  ///< "metric", "local_weights", "shrink_correction", and "clamp" with --clamp
    std::vector<std::pair<std::string, double>> stage_seconds;  ///< wall time of each stage, in order
    std::optional<BlockLayout> block_layout;  ///< the blocks of a block-wise run (streaming or MPI)
    // Label maps only (--multi-label; empty otherwise):
    std::vector<LabelMesh> label_meshes;        ///< the closed surface of each label
    std::vector<LabelMeasures> label_measures;  ///< faces, area, volume, topology of each
    Junctions junctions;                        ///< junction vertices and edges of the complex
};

/// Surface, normals and regularization of `loaded` (stages "surface", "normals", "at",
/// "regularize"; each reported to `progress` as it starts and ends). Checks the options first.
/// Throws dsreg::Error.
PipelineResult run_pipeline(const LoadedVolume& loaded, const PipelineOptions& options,
                            const ProgressCallback& progress = {});

/// The same from a file or shape: load_volume (stage "read" or "digitize"), the --max-memory
/// check on the counted surfels, then the stages above; local weight maps are read with the
/// source's raw layout and voxel limit.
PipelineResult run_pipeline(const VolumeSource& source, const PipelineOptions& options,
                            const ProgressCallback& progress = {});

/// The output mesh: the regularized vertices (or the digital ones with `digital`), the quads (or
/// triangles, split along the shorter diagonal), the field u per face and, after AT, the feature
/// map v per vertex ("v"); in the grid frame (output_mesh maps it to the output space).
PolygonMesh result_mesh(const PipelineResult& result, bool triangulate, bool digital = false);

/// Where the results go; empty paths are not written.
struct PipelineOutputs {
    std::string mesh;          ///< -o: .obj .off .ply .stl .vtk .vtp (empty in the Python module, which returns the mesh)
    std::string input_mesh;    ///< --input-mesh: the digital surface
    std::string normals;       ///< --export-normals: the field u in the --normals-file format
    std::string features;      ///< --features: AT feature lines as OBJ polylines
    std::string report;        ///< --report: JSON
    std::string html;          ///< --html: a self-contained page showing the result (result_page)
    std::string fragments;     ///< --fragments DIR: one mesh per block and manifest.json (block-wise runs)
    bool triangulate = false;  ///< --triangulate
    /// --space: the coordinates of the meshes and feature lines (world_space.hpp). The files record
    /// it as 3D Slicer does ("SPACE=LPS") when the input has a world geometry (medical formats,
    /// arrays given with an affine). The --export-normals file stays in the grid frame (it is read
    /// back by --normals-file).
    OutputSpace space = OutputSpace::Lps;

    /// Whether any file is to be written.
    bool any() const {
        return !mesh.empty() || !input_mesh.empty() || !normals.empty() || !features.empty() || !report.empty() ||
               !html.empty() || !fragments.empty();
    }
};

/// The file of one label's surface next to -o: "out.ply" and label 7 give "out-7.ply".
std::string label_output_path(const std::string& mesh_path, std::int64_t value);

/// The output mesh of result_mesh() in `space`, tagged with its coordinate system when the input
/// file has a world geometry. Triangles are split in the grid frame, where lengths are physical.
PolygonMesh output_mesh(const PipelineResult& result, const PipelineOutputs& outputs, bool digital = false);

/// The closed surface of the label result.label_meshes[index], oriented outward, as it is written
/// next to -o (label_output_path): its own vertices, bit for bit the complex's positions in
/// output_mesh() (the same map of the same points), the field u flipped where the label is the
/// outer one, triangles with outputs.triangulate.
PolygonMesh output_label_mesh(const PipelineResult& result, const PipelineOutputs& outputs, std::size_t index);

/// The --html page (html_view.hpp): one layer, the regularized surface as quads (also with
/// --triangulate: the split is the user's output format, not the result) with the digital surface
/// as a toggle, the field u, the feature map v and its lines after AT; and the run's summary:
/// input, grid, counts, field, weights, solve, energies, per-stage seconds and peak memory so far.
/// Lengths are the volume's physical units, in the grid frame (not --space).
ViewPage result_page(const PipelineResult& result, const PipelineOptions& options);

/// Checks the output paths (extensions, folders, two outputs on one file) before any work.
void check_pipeline_outputs(const PipelineOutputs& outputs);

/// Writes every output (each atomically), the report last; adds the "write" stage to `result`.
/// For a label map, -o holds every interface face once with the int face properties
/// inner_label and outer_label (label values; the face normal points from inner to outer), and
/// label_output_path(-o, value) the closed surface of each label, oriented outward.

/// Writes every output (each atomically; the page after the meshes, the report last); adds the
/// "write" stage to `result`.
void write_pipeline_outputs(PipelineResult& result, const PipelineOptions& options, const PipelineOutputs& outputs,
                            const VolumeSource& source, const ProgressCallback& progress = {});

/// The --report content: input (format, value type, notes, warnings), grid (with direction),
/// output space and the affine maps to it, counts, parameters, solve, energies, per-stage
/// seconds, peak memory, outputs.
nlohmann::json pipeline_report(const PipelineResult& result, const PipelineOptions& options,
                               const PipelineOutputs& outputs, const VolumeSource& source);

/// The one-line summary the CLI prints, without the "dsreg: " prefix, e.g. "goursat at h=0.25:
/// 37590 surfels, 37592 vertices, 1 component; energy 1382 -> 0.4711; amg residual 4.0e-09;
/// 0.59 s, 109.1 MiB peak".
std::string summary_line(const PipelineResult& result, const PipelineOptions& options);

/// Peak resident memory of this process so far, in bytes.
std::int64_t peak_memory_bytes();

/// "1.5 GiB", "230 MiB", ...
std::string human_bytes(double bytes);

}  // namespace dsreg
