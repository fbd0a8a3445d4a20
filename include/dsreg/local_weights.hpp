// dsreg — sources of the local multipliers α_i, β_f, γ_i of the regularization energy
// (RegularizationWeights::vertex_alpha, face_beta, vertex_gamma; beyond the paper).
//
// Four sources:
//  * a scalar volume on the same voxel grid as the binary volume the surface came from (e.g. a
//    confidence or probability map of a segmentation), sampled at the vertices: the value of a
//    vertex is the mean of the values of the 8 voxels around its pointel — voxels (a−1 … a,
//    b−1 … b, c−1 … c) for pointel (a,b,c), see volume.hpp — leaving out those outside the
//    grid; the value of a face is the mean of its 4 vertex values;
//  * a text file holding one value per vertex (or per face) in mesh order: the vertex and face
//    order of the surface (DigitalSurface::vertices / quads), which is also the order of the
//    written mesh files. Numbers are separated by whitespace; '#' starts a comment that runs to
//    the end of the line.
//  * the local reach of the surface (local_reach.hpp): a stronger data term on thin parts
//    (thin_part_alpha);
//  * the faces whose estimated normal points against their surfel: a stronger fairness term
//    where the voxels are noisy (noise_fairness_gamma).
// Values are used as given (dimensionless multipliers); validate_weights() rejects α_i ≤ 0 and
// β_f, γ_i < 0.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/volume_io.hpp"

namespace dsreg {

/// Mean of the values of the voxels around each vertex's pointel that lie in the grid (at least
/// one always does). Throws dsreg::Error unless the volume has the surface grid's dims.
Eigen::VectorXd sample_at_vertices(const ScalarVolume& volume, const DigitalSurface& surface);

/// Mean of the per-vertex values over the vertices of each face.
Eigen::VectorXd face_means(const FaceMatrix& faces, const Eigen::VectorXd& vertex_values);

/// Reads exactly `expected_count` numbers from a text file (format above). `what` names the
/// values in messages (e.g. "per-vertex alpha"). Throws dsreg::Error "PATH:LINE: problem" for a
/// token that is not a finite number, and "PATH: …" for too few or too many values.
Eigen::VectorXd read_values_file(const std::string& path, std::int64_t expected_count, const std::string& what);

/// The data-term multipliers α_i = max(1, (reference / ρ_i)²) of a surface whose faces have the
/// reach `face_reach` (physical units, e.g. SurfelReach::smallest()), ρ_i being the smallest
/// reach of the faces around vertex i. Why: the alignment term is a sum of squared edge
/// lengths, so shrinking a part lowers it; against the data term α|p̂ − p|² that shrink costs
/// α·ρ² on a part of reach ρ, so with one α a part shrinks more the thinner it is (a tube 2.4
/// voxels in radius loses half its volume with α = 1e-3). With α ∝ 1/ρ² below the reference the
/// balance, and so the relative shrink, no longer depends on the thickness (docs/accuracy.md).
/// A sheet has no such lever (thin_part_shape.hpp): with `face_sheetness` (one value in [0, 1]
/// per face; empty: every thin part is a tube) the reference of face f is blended from
/// `reference` (a tube) to `sheet_reference` (a sheet), R_f = R − s_f·(R − R_sheet), and α_i is
/// the largest max(1, (R_f/ρ_f)²) over the faces around vertex i (ρ_f: face_reach).
/// Throws dsreg::Error for a reference that is not positive and finite, a sheet reference that
/// is negative or not finite, or a wrong face count.
Eigen::VectorXd thin_part_alpha(const DigitalSurface& surface, const Eigen::VectorXd& face_reach, double reference,
                                const Eigen::VectorXd& face_sheetness = {}, double sheet_reference = 0);

/// The fairness multipliers γ_i = 1 + gain · min(1, ρ_i / full_share)² where the voxels are
/// noisy. ρ_i is the share of faces pointing against their surfel (faces_against_their_surfels,
/// normals.hpp) around vertex i: the indicator of those faces averaged from faces to vertices and
/// back `rings` times, then to the vertices (each pass widens the neighbourhood by about one
/// ring). Why: on a bump or a pit of flipped voxels the alignment term flattens the quads along u
/// and collapses their side walls into slivers of arbitrary normal, which only the fairness term
/// spreads out again; a clean digitization of a smooth object has next to no such faces, so its
/// weights stay 1 (docs/accuracy.md, "Noisy voxels"). Throws dsreg::Error for a negative or
/// non-finite gain, a full share outside (0, 1], rings < 0 or a face index out of range.
Eigen::VectorXd noise_fairness_gamma(const DigitalSurface& surface, const std::vector<std::int32_t>& faces_against_surfels,
                                     double gain, double full_share, int rings);

/// Writes one value per line with 17 significant digits, so read_values_file() gives back the
/// same doubles (atomic write).
void write_values_file(const std::string& path, const Eigen::VectorXd& values);

}  // namespace dsreg
