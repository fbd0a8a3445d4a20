// dsreg — a volume cut into blocks: voxel boxes, the global identity of surfels and vertices,
// the piece of the digital surface each block needs (its patch), and the welding of the blocks'
// results into one mesh. Used by the block-wise streaming mode (`--block-size`, streaming.hpp)
// and by the MPI driver (distributed.hpp); plain data, no MPI.
//
// Global identity. The whole-volume extraction (digital_surface.hpp) lists the surfels in the
// order of their key 6·(linear index of the voxel) + 2·axis + (sign > 0), and numbers the vertices
// (one per umbrella of a pointel) in the order of their first face corner. So
//   surfel key  = 6·(i + nx·(j + ny·k)) + 2·axis + (sign > 0)
//   vertex key  = min over the corners of its umbrella of 4·(surfel key) + corner
// give every face and vertex a name that any block computes alike from the voxels around it
// (an umbrella depends only on the 8 voxels around its pointel), and sorting by key gives back
// the whole-volume order: face f of the whole surface is the f-th smallest surfel key, vertex i
// the i-th smallest vertex key. A split pointel (several umbrellas) has one key per umbrella.
//
// Ownership. A block owns the surfels of its voxels, and the vertices whose key surfel (the
// surfel of the smallest corner of the umbrella) it owns. Every face and every vertex has exactly
// one owner, whichever way the grid is cut.
//
// Patches. The row of vertex j in R (eq. 22–23) involves the faces around j, the links of j's
// neighbours and the fairness 2-ring. For the vertices keyed in a box B ("row vertices"), every such
// face has its voxel in B grown by 2 voxels (kPatchFaceMargin), and the umbrellas of their
// vertices depend on the voxels of B grown by 3; the surfels and edge pairings of those voxels on
// B grown by 4 (kPatchVolumeMargin). A patch extracted from B + 4 and cut to the faces of B + 2
// thus gives rows that are bit for bit those of the whole surface (same terms, summed in the same
// order, since the patch keeps the global order of faces and vertices).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/volume.hpp"

namespace dsreg {

/// A grid of dims voxels cut into blocks: along axis a, block b spans cuts[a][b] ≤ index <
/// cuts[a][b+1] (cuts[a] starts at 0, ends at dims[a], strictly increasing). Blocks are numbered
/// x fastest, like voxels.
struct BlockLayout {
    Index3 dims{0, 0, 0};
    std::array<std::vector<std::int64_t>, 3> cuts;

    Index3 block_counts() const;
    std::int64_t block_count() const;
    VoxelBox box(std::int64_t block) const;
    /// The block holding voxel (i,j,k) of the grid.
    std::int64_t block_of(const Index3& voxel) const;
};

/// Blocks of block_size voxels (the last ones along each axis may be smaller). Throws
/// dsreg::Error unless every size is positive.
BlockLayout blocks_of_size(const Index3& dims, const Index3& block_size);

/// `parts` blocks of nearly equal size: parts = px·py·pz with the factors as equal as possible,
/// the largest along the longest axis (no factor larger than the grid along its axis). Throws
/// dsreg::Error if the grid has fewer voxels along its axes than that allows.
BlockLayout blocks_for_parts(const Index3& dims, int parts);

/// The blocks centred on the cuts of `layout`: along each axis, cuts at the middles of its blocks
/// (so that every cut of `layout` runs through the middle of one of these blocks).
BlockLayout staggered_blocks(const BlockLayout& layout);

/// Global keys (see above).
std::int64_t surfel_key(const Index3& dims, const Index3& voxel, int axis, int sign);
/// The surfel of a key, in the grid's voxel coordinates.
Surfel surfel_of_key(const Index3& dims, std::int64_t key);
/// The voxel of the surfel whose corner names a vertex key (the vertex's owner voxel).
Index3 key_voxel_of_vertex(const Index3& dims, std::int64_t vertex_key);
/// The pointel of a vertex key, in the grid's pointel coordinates.
Index3 pointel_of_vertex_key(const Index3& dims, std::int64_t vertex_key);

/// The key of every vertex of `surface`, whose voxel coordinates start at `offset` in a grid of
/// `dims` voxels: the smallest 4·(surfel key) + corner over the vertex's corners (its key if its
/// umbrella lies whole in `surface`, as for every vertex of a whole surface).
std::vector<std::int64_t> vertex_keys_of(const DigitalSurface& surface, const Index3& offset, const Index3& dims);

/// Margins of a patch around its box of row vertices (see above).
constexpr std::int64_t kPatchFaceMargin = 2;
constexpr std::int64_t kPatchVolumeMargin = 4;

/// The piece of the digital surface a block needs: the faces whose voxel lies in `rows` + 2,
/// and their vertices, in the global order (sorted by key).
struct SurfacePatch {
    /// The faces and vertices, as a DigitalSurface on the grid of the volume it was extracted from
    /// (surfels, vertex_pointels and grid in that volume's coordinates, so the normal estimators
    /// can run on it), except `vertices`: the positions p on the whole grid, computed exactly as
    /// the whole-volume extraction does. The patch is open: adjacent_face is −1 across its
    /// border, and it has no components (component_count 0).
    DigitalSurface surface;
    std::vector<std::int64_t> face_keys;    ///< ascending
    std::vector<std::int64_t> vertex_keys;  ///< ascending
    std::vector<char> face_owned;           ///< the face's voxel is in the owned box
    std::vector<char> vertex_owned;         ///< the vertex's key surfel is in the owned box
    std::vector<char> vertex_row;           ///< the vertex's key surfel is in the rows box: its row of R is exact

    std::int64_t face_count() const { return surface.face_count(); }
    std::int64_t vertex_count() const { return surface.vertex_count(); }
};

/// The patch of the vertices keyed in `rows` (owned ⊆ rows, both boxes of the whole grid).
/// `volume` holds the voxels of `volume_box` of the whole grid `grid` (its own grid: the same
/// spacing, dims = volume_box.size()); it must cover rows + kPatchVolumeMargin + surface_margin
/// (clipped to the grid). `surface_margin` (voxels) widens the patch for normal estimators that
/// read the surface around a face (convolved trivial normals): the faces of rows + 2 +
/// surface_margin are kept. Throws dsreg::Error if the volume is too small. An empty patch (no
/// faces) is not an error.
SurfacePatch extract_surface_patch(const BinaryVolume& volume, const VoxelBox& volume_box, const VoxelGrid& grid,
                                   const VoxelBox& owned, const VoxelBox& rows, Connectivity connectivity,
                                   std::int64_t surface_margin = 0);

/// The voxels of `box` (inside `volume_box`) of a volume that holds `volume_box`, with its own grid.
BinaryVolume crop_volume(const BinaryVolume& volume, const VoxelBox& volume_box, const VoxelBox& box);

/// What a block keeps of its result: its own faces and vertices, named by their global keys.
struct BlockPiece {
    std::vector<std::int64_t> face_keys;                  ///< owned faces, ascending
    std::vector<std::array<std::int64_t, 4>> face_corners;  ///< vertex keys of their corners
    std::vector<std::array<std::int64_t, 4>> face_neighbors;  ///< surfel keys of the faces across their edges
    PointMatrix face_normals;                             ///< the field u on them
    std::vector<std::int64_t> vertex_keys;                ///< owned vertices, ascending
    PointMatrix positions;                                ///< their regularized positions
};

/// The owned faces and vertices of a patch, with `positions` (one row per patch vertex) and the
/// field `normals` (one row per patch face).
BlockPiece patch_piece(const SurfacePatch& patch, const PointMatrix& positions, const PointMatrix& normals);

/// The whole surface welded from the pieces of every block (consumed): faces and vertices in
/// the whole-volume order (so surface, normals and positions equal the whole-volume pipeline's
/// up to the solver's error), adjacency from the pieces' neighbour keys, components relabelled.
struct WeldedSurface {
    DigitalSurface surface;  ///< positions p in `vertices`, as extract_digital_surface gives them
    PointMatrix normals;     ///< u, one row per face
    PointMatrix positions;   ///< regularized positions, one row per vertex
};

/// Throws dsreg::Error if the pieces do not fit together into a closed oriented 2-manifold (a
/// face or vertex owned twice, a corner or neighbour that no piece holds, a neighbour that does
/// not have the same edge the other way round): the seams of the blocks would not be watertight.
WeldedSurface weld_pieces(std::vector<BlockPiece>& pieces, const VoxelGrid& grid);

}  // namespace dsreg
