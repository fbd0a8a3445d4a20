// dsreg — normal vector fields in a text file, so that any external estimator can be plugged in
// (`dsreg regularize --normals-file F`) and the field dsreg used can be inspected or reused
// (`--export-normals F`).
//
// Format (UTF-8/ASCII text, one surfel per line, any order):
//
//   # dsreg normals: i j k direction nx ny nz
//   12 7 3 +x 0.9813 0.1402 0.1316
//   12 7 3 -z 0.1103 -0.0291 -0.9935
//
//  * i j k: the 0-based index of the surfel's object voxel in the volume grid (a file's own voxel
//    coordinates; for --shape, the digitization grid of the --report's "grid": voxel (0,0,0) is
//    at "origin"). Decimal integers.
//  * direction: the side of that voxel the face is on, one of +x -x +y -y +z -z (x, y, z may be
//    upper case): the voxel (i,j,k) + direction is background. This is the surfel's trivial
//    normal, so "+x" is the face with normal (1,0,0).
//  * nx ny nz: the normal, pointing out of the object, in physical coordinates. Decimal numbers
//    (C syntax: 1, -0.5, 2.5e-3). It must be finite and non-zero; it is divided by its length
//    unless that length is already 1 to within 1e-12 (so an exported field reads back bit for bit).
//  * '#' starts a comment (to the end of the line); blank lines are ignored; fields are separated
//    by spaces or tabs; lines end with LF or CRLF and hold at most 1024 characters; a UTF-8 byte
//    order mark at the start is skipped.
//
// Every surfel of the surface must appear exactly once. Reading checks everything and throws
// dsreg::Error "FILE:LINE: problem" for a malformed line, a voxel outside the grid, a face that
// is not a surfel of the surface, a surfel given twice (naming both lines), a non-numeric, zero,
// infinite or NaN normal; and "FILE: …" naming the first surfel without a line. Memory is
// proportional to the surface, never to the file.
#pragma once

#include <istream>
#include <string>

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"

namespace dsreg {

/// "+x", "-x", "+y", "-y", "+z" or "-z".
std::string surfel_direction_name(const Surfel& surfel);

/// Reads the normal of every surfel of `surface` from the file at `path` (format above): row f
/// of the result is the unit normal of face f.
PointMatrix read_normals_file(const std::string& path, const DigitalSurface& surface);

/// Same, from a stream; `name` is the file name used in messages.
PointMatrix read_normals(std::istream& in, const std::string& name, const DigitalSurface& surface);

/// Writes one line per face of `surface` in face order, numbers in their shortest exact decimal
/// form, after a commented header that explains the columns and holds `description`. Atomic
/// write; throws dsreg::Error naming `path` if `normals` is not m×3 or on I/O failure.
void write_normals_file(const std::string& path, const DigitalSurface& surface, const PointMatrix& normals,
                        const std::string& description = "");

}  // namespace dsreg
