// dsreg — mesh files: OBJ, OFF, PLY (binary little-endian; ASCII too on reading), STL, and
// 3D Slicer's model formats VTK legacy PolyData (.vtk) and VTK XML PolyData (.vtp).
//
// The format is chosen by the file extension, in any case: .obj, .off, .ply, .stl, .vtk, .vtp.
//
// Coordinate system (PolygonMesh::coordinate_system, "LPS" or "RAS"): written where 3D Slicer's
// vtkMRMLModelStorageNode writes and looks for it, so that Slicer places the mesh without asking:
// "SPACE=LPS" in the header line of .vtk, the FieldData string array SPACE = "LPS" of .vtp, the
// 80-byte header of binary STL, a "comment SPACE=LPS" line of PLY, the first comment line of OBJ
// (and, for OFF, which Slicer does not read, a comment after "OFF"). Readers restore it from the
// same place by Slicer's rule ("SPACE=RAS", else "SPACE=LPS", else unspecified).
//
// Writing (atomic: a failure never leaves a partial file nor touches an existing one). The mesh
// is checked first: faces must have 3 or 4 vertices, every index must address a vertex,
// coordinates must be finite, face_normals must be empty or have one row per face, and every
// vertex scalar must have one value per vertex. Positions in text formats use the shortest
// decimal form that reads back to the same double.
//  * OBJ: "v x y z" and "f i j k [l]" lines (1-based). Quads stay quads. No attributes.
//  * OFF: "OFF", counts, vertex lines, "n i j k [l]" face lines. Quads stay quads. No attributes.
//  * PLY: binary_little_endian 1.0; vertex x y z as double plus one float property per vertex
//    scalar (names must be single words other than x, y, z); face "list uchar int
//    vertex_indices" plus float nx ny nz when face_normals is set, then one int property per
//    face integer (single words other than nx, ny, nz, vertex_indices).
//  * STL: binary; quads are split along their shorter diagonal; each facet normal is the unit
//    geometric normal of its triangle, or 0 for a degenerate triangle.
//  * VTK: legacy "# vtk DataFile Version 4.2" (what Slicer writes), BINARY; POINTS double,
//    POLYGONS (quads stay quads), CELL_DATA NORMALS "u" with face_normals, POINT_DATA SCALARS
//    per vertex scalar (names must be single words).
//  * VTP: XML PolyData, inline base64 binary arrays (UInt64 headers, no compression): Points
//    Float64, Polys Int64 connectivity and offsets, CellData "u", PointData per vertex scalar.
//
// Reading. Only triangles and quads are accepted: a face with fewer than 3 or more than 4
// vertices is an error (n-gons are not fan-triangulated, which would be wrong for non-convex
// polygons). When a file mixes triangles and quads, the quads are split along their shorter
// diagonal (face normals duplicated) so that all faces have the same size; a file without
// faces gives a 0×3 face matrix. Vertex coordinates must be finite. Every count is checked
// against the size of the file before memory is allocated for it.
//  * OBJ: "v x y z [w]" (or with r g b) and "f" with vertex references i, i/t, i/t/n or i//n;
//    negative indices count back from the last vertex defined; a face may only use vertices
//    defined before it. vt, vn, vp, g, o, s, mg, usemtl, mtllib, l, p and the free-form
//    geometry statements are ignored; any other statement is an error. '#' starts a comment.
//  * OFF: one vertex or face per line; '#' comments; counts may follow "OFF" on its line; the
//    C/N/ST variants (COFF, NOFF, ...) are accepted, extra numbers on vertex lines and face
//    colours are ignored; binary OFF, 4OFF and nOFF are rejected.
//  * PLY: ascii, binary_little_endian, binary_big_endian. Element "vertex" needs scalar
//    properties x, y, z of any numeric type; its other scalar properties become vertex_scalars
//    (same name, read as double), its list properties are skipped. Element "face" needs a list
//    "vertex_indices" (or "vertex_index") of integers; scalar properties nx, ny, nz (all three)
//    become face_normals; other scalar properties of an integer type become face_integers
//    (duplicated with their quad when quads are split); other properties are skipped. Other
//    elements are skipped.
//  * STL: ASCII (starts with "solid", several solids allowed) or binary (size 84 + 50 × the
//    triangle count of the header). Identical positions are merged, so the mesh is indexed;
//    the facet normals of the file are not kept.
//  * VTK: ASCII or BINARY; POINTS of any numeric type; POLYGONS in the 4.2 layout or the 5.1
//    OFFSETS/CONNECTIVITY layout; VERTICES and LINES skipped, TRIANGLE_STRIPS rejected;
//    CELL_DATA NORMALS become face_normals, POINT_DATA SCALARS of one component become
//    vertex_scalars, other attribute arrays are skipped. Only DATASET POLYDATA is accepted.
//  * VTP: what VTK's XML writer writes: ascii, inline binary or appended (raw or base64) arrays,
//    UInt32 or UInt64 headers, no compression or vtkZLibDataCompressor, either byte order; one
//    Piece; Verts and Lines skipped, Strips rejected; the CellData Normals array (or "u") gives
//    face_normals, PointData arrays of one component give vertex_scalars.
#pragma once

#include <string>

#include "dsreg/mesh.hpp"

namespace dsreg {

/// Splits every quad (a,b,c,d) into two triangles along its shorter diagonal, keeping the
/// orientation: (a,b,c),(a,c,d) when |ac| <= |bd|, else (a,b,d),(b,c,d). Face normals and face
/// integers are duplicated per triangle, vertices and vertex scalars are kept. Triangle meshes
/// are returned unchanged. Throws dsreg::Error for faces of another size or indices out of range.
PolygonMesh triangulate_shorter_diagonal(const PolygonMesh& mesh);

/// The checks write_mesh makes before writing (see above: face sizes, indices, finite
/// coordinates, attribute sizes). Throws dsreg::Error whose message starts with `context`.
void check_mesh(const std::string& context, const PolygonMesh& mesh);

/// Writes `mesh` in the format named by the extension of `path` (see above). Atomic write.
/// Throws dsreg::Error naming `path` for an unknown extension, an invalid mesh or an I/O failure.
void write_mesh(const std::string& path, const PolygonMesh& mesh);

/// Reads an OBJ, OFF, PLY or STL mesh of triangles and/or quads (see above). Throws dsreg::Error
/// naming the file (and the line, for text) on a missing file or malformed input.
PolygonMesh read_mesh(const std::string& path);

}  // namespace dsreg
