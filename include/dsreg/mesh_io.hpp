// dsreg — mesh files: OBJ, OFF, PLY (binary little-endian; ASCII too on reading), STL.
#pragma once

#include <string>

#include "dsreg/mesh.hpp"

namespace dsreg {

/// Splits every quad (a,b,c,d) into two triangles along its shorter diagonal, keeping the
/// orientation. Triangle meshes are returned unchanged. Face normals are duplicated per triangle.
PolygonMesh triangulate_shorter_diagonal(const PolygonMesh& mesh);

/// Writes `mesh` in the format named by the extension of `path`: .obj, .off, .ply, .stl.
/// OBJ/OFF/PLY keep quads; PLY also stores face_normals (as nx, ny, nz face properties) and the
/// vertex_scalars; STL always holds triangles (quads are split as above). Atomic write.
/// Throws dsreg::Error for an unknown extension or an I/O failure.
void write_mesh(const std::string& path, const PolygonMesh& mesh);

/// Reads an OBJ, OFF or PLY (ASCII or binary) or STL (ASCII or binary) mesh of triangles and/or
/// quads (a mixed mesh is triangulated). Throws dsreg::Error naming the file on malformed input.
PolygonMesh read_mesh(const std::string& path);

}  // namespace dsreg
