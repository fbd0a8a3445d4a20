#!/usr/bin/env python3
"""Writes the hand-made hostile inputs of fuzz/regressions/<target>/hostile-* (committed).

Each file is one attack on a reader: truncated payloads, lying headers, zlib bombs, dimensions
of 2^31, negative sizes, non-numeric fields. fuzz/regressions/expected-messages.tsv lists the
message each must be rejected with (checked by the fuzz_regressions test), and
docs/hostile-inputs.md shows the actual messages. Run from anywhere:
    python3 fuzz/regressions/make_hostile.py
"""
import os
import struct
import zlib

ROOT = os.path.dirname(os.path.abspath(__file__))


def put(target, name, data):
    folder = os.path.join(ROOT, target)
    os.makedirs(folder, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(folder, "hostile-" + name), "wb") as f:
        f.write(data)


def vol_header(x, y, z, version, extra=""):
    return f"X: {x}\nY: {y}\nZ: {z}\nVoxel-Size: 1\n{extra}Version: {version}\n.\n"


def raw_prefix(x, y, z, type_code, big_endian=False, header_bytes=0):
    return struct.pack("<iiiBBB", x, y, z, type_code, 1 if big_endian else 0, header_bytes)


# ---- .vol
put("vol", "truncated-v2.vol", vol_header(4, 4, 4, 2) + "abc")
put("vol", "trailing-v2.vol", vol_header(2, 2, 1, 2) + "\x01\x00\x01\x00EXTRA")
put("vol", "dims-2p31.vol", vol_header(2**31, 2**31, 2**31, 2) + "\x01")
put("vol", "negative-dim.vol", vol_header(-4, 4, 4, 2) + "\x00" * 64)
put("vol", "non-numeric-dim.vol", vol_header("four", 4, 4, 2) + "\x00" * 64)
put("vol", "dim-overflows-int64.vol", vol_header(99999999999999999999999, 1, 1, 2) + "\x00")
put("vol", "lying-header-v3.vol", vol_header(2000, 2000, 2000, 3).encode() + zlib.compress(b"\x01" * 64))
# A zlib bomb: 32 MiB of zeros in 32 KiB, for a header announcing 16 voxels.
put("vol", "zlib-bomb.vol", vol_header(4, 2, 2, 3).encode() + zlib.compress(b"\x00" * (32 << 20), 9))
put("vol", "zlib-short.vol", vol_header(4, 4, 4, 3).encode() + zlib.compress(b"\x01" * 60))
put("vol", "zlib-corrupt.vol", vol_header(4, 4, 4, 3).encode() + b"\x78\x9c" + b"\xff" * 30)
put("vol", "zlib-cut.vol", vol_header(4, 4, 4, 3).encode() + zlib.compress(b"\x01" * 64)[:-6])
put("vol", "no-end-line.vol", "X: 4\nY: 4\nZ: 4\nVersion: 2\n")
put("vol", "version-4.vol", vol_header(1, 1, 1, 4) + "\x01")
put("vol", "voxel-size-2.vol", "X: 1\nY: 1\nZ: 1\nVoxel-Size: 2\nVersion: 2\n.\n\x01\x00")
put("vol", "duplicate-key.vol", "X: 1\nX: 2\nY: 1\nZ: 1\nVersion: 2\n.\n\x01")
put("vol", "binary-garbage.vol", bytes(range(256)) * 4)

# ---- .longvol
put("longvol", "truncated-v2.longvol", vol_header(2, 2, 2, 2).replace("Voxel-Size: 1", "Lvoxel-Size: 8") + "\x01" * 60)
put("longvol", "dims-2p31.longvol", vol_header(2**31 - 1, 2**31 - 1, 1, 3).encode() + zlib.compress(b"\x00" * 8))
put("longvol", "lying-header-v3.longvol", vol_header(1000, 1000, 1000, 3).encode() + zlib.compress(b"\x00" * 800))

# ---- .pgm3d
put("pgm3d", "bad-magic.pgm3d", "P5-2D\n2 2 2\n255\n" + "\x01" * 8)
put("pgm3d", "maxval-zero.pgm3d", "P5-3D\n2 2 2\n0\n" + "\x00" * 8)
put("pgm3d", "maxval-70000.pgm3d", "P5-3D\n2 2 2\n70000\n" + "\x00" * 16)
put("pgm3d", "value-above-maxval.pgm3d", "P2-3D\n2 1 1\n10\n5 11\n")
put("pgm3d", "non-numeric-value.pgm3d", "P2-3D\n2 1 1\n10\n5 x1\n")
put("pgm3d", "negative-dim.pgm3d", "P2-3D\n-2 1 1\n10\n5 1\n")
put("pgm3d", "dims-2p31.pgm3d", "P5-3D\n2147483648 2147483648 2147483648\n255\n\x00")
put("pgm3d", "lying-ascii-header.pgm3d", "P2-3D\n1000 1000 1000\n255\n1 2 3 4\n")
put("pgm3d", "truncated-p5.pgm3d", "P5-3D\n4 4 4\n65535\n" + "\x00" * 100)
put("pgm3d", "trailing-p2.pgm3d", "P2-3D\n2 1 1\n10\n5 1 7\n")

# ---- .raw (15-byte layout prefix, then the file; see fuzz_targets.hpp)
put("raw", "negative-dim", raw_prefix(-1, 4, 4, 0) + b"\x00" * 16)
put("raw", "dims-2p31", raw_prefix(2**31 - 1, 2**31 - 1, 2**31 - 1, 9) + b"\x00" * 8)
put("raw", "truncated-int16", raw_prefix(4, 4, 4, 3) + b"\x00" * 127)
put("raw", "header-beyond-file", raw_prefix(1, 1, 1, 0, header_bytes=200) + b"\x01" * 10)

# ---- polynomials
put("polynomial", "huge-power", "(x+y+z)^1000000")
put("polynomial", "degree-65", "(x+y)^33*(z-1)^32")
put("polynomial", "syntax", "x^2+*y")
put("polynomial", "implicit-product", "2x+y")
put("polynomial", "nested-20000", "(" * 20000 + "x" + ")" * 20000)
put("polynomial", "overflowing-coefficient", "1e999*x")
put("polynomial", "power-tower", "x^2^3")

# ---- normals files (surface: fuzz_targets.cpp, normals_target_surface)
put("normals", "nan-normal", "0 0 0 -x nan 0 0\n")
put("normals", "zero-normal", "0 0 0 -x 0 0 0\n")
put("normals", "voxel-2p63", "9223372036854775807 0 0 -x -1 0 0\n")
put("normals", "negative-voxel", "-1 0 0 -x -1 0 0\n")
put("normals", "non-numeric", "0 0 0 -x minus-one 0 0\n")
put("normals", "long-line", "0 0 0 -x -1 0 0 " + "9" * 5000 + "\n")
put("normals", "duplicate", "0 0 0 -x -1 0 0\n0 0 0 -x -1 0 0\n")
put("normals", "missing-surfels", "0 0 0 -x -1 0 0\n")
put("normals", "not-a-surfel", "1 1 1 +x 1 0 0\n")

# ---- meshes
put("obj", "index-out-of-range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
put("obj", "nan-vertex.obj", "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
put("obj", "pentagon.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\nf 1 2 3 4 5\n")
put("obj", "index-2p31.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2147483648\n")
put("obj", "unknown-statement.obj", "v 0 0 0\nfoo 1 2 3\n")
put("off", "counts-2p31.off", "OFF\n2147483647 2147483647 0\n0 0 0\n")
put("off", "negative-count.off", "OFF\n-3 1 0\n0 0 0\n")
put("off", "truncated.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n")
put("off", "non-numeric.off", "OFF\n3 1 0\n0 0 zero\n1 0 0\n0 1 0\n3 0 1 2\n")
put("ply", "vertex-count-2p32.ply",
    "ply\nformat binary_little_endian 1.0\nelement vertex 4294967296\nproperty float x\nproperty float y\n"
    "property float z\nend_header\n" + "\x00" * 12)
put("ply", "truncated-binary.ply",
    "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
    "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" + "\x00" * 50)
put("ply", "list-count-255.ply",
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n255 0 1 2\n")
put("ply", "negative-count.ply",
    "ply\nformat ascii 1.0\nelement vertex -3\nproperty float x\nproperty float y\nproperty float z\nend_header\n")
put("ply", "no-end-header.ply", "ply\nformat ascii 1.0\nelement vertex 3\n")
put("stl", "triangle-count-2p31.stl", b"\x00" * 80 + struct.pack("<I", 2**31 - 1) + b"\x00" * 50)
put("stl", "truncated-ascii.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n")
put("stl", "nan-ascii.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 nan\nvertex 1 0 0\nvertex 0 1 0\n"
    "endloop\nendfacet\nendsolid t\n")


# ---- NIfTI (348-byte NIfTI-1 header written field by field)
def nifti1(dims, datatype=2, bitpix=8, vox_offset=352.0, magic=b"n+1\0", pixdim=(1, 1, 1, 1), slope=1.0):
    header = bytearray(352)
    struct.pack_into("<i", header, 0, 348)
    struct.pack_into("<8h", header, 40, len(dims), *(list(dims) + [1] * (7 - len(dims))))
    struct.pack_into("<hh", header, 70, datatype, bitpix)
    struct.pack_into("<8f", header, 76, *(list(pixdim) + [1] * (8 - len(pixdim))))
    struct.pack_into("<fff", header, 108, vox_offset, slope, 0.0)
    header[344:348] = magic
    return bytes(header)


put("nifti", "truncated.nii", nifti1((64, 64, 64)) + b"\x01" * 100)
put("nifti", "lying-gzip.nii.gz", __import__("gzip").compress(nifti1((2000, 2000, 2000)) + b"\x01" * 64))
put("nifti", "header-size-1000.nii", struct.pack("<i", 1000) + b"\x00" * 400)
put("nifti", "time-series.nii", nifti1((4, 3, 2, 5)) + b"\x01" * 120)
put("nifti", "vector.nii", nifti1((4, 3, 2, 1, 3)) + b"\x01" * 72)
put("nifti", "rgb.nii", nifti1((4, 3, 2), datatype=128, bitpix=24) + b"\x01" * 72)
put("nifti", "negative-dim.nii", nifti1((4, -3, 2)) + b"\x01" * 24)
put("nifti", "dims-32767.nii", nifti1((32767, 32767, 32767)) + b"\x01" * 24)
put("nifti", "vox-offset-inside-header.nii", nifti1((2, 2, 2), vox_offset=100.0) + b"\x01" * 8)
put("nifti", "vox-offset-nan.nii", nifti1((2, 2, 2), vox_offset=float("nan")) + b"\x01" * 8)
put("nifti", "pair-without-img.nii", nifti1((2, 2, 2), magic=b"ni1\0"))

# ---- NRRD
NRRD = "NRRD0004\ntype: {type}\ndimension: {dimension}\nsizes: {sizes}\nencoding: {encoding}\n{extra}\n"
put("nrrd", "lying-raw.nrrd", NRRD.format(type="short", dimension=3, sizes="2000 2000 2000", encoding="raw",
                                          extra="endian: little\n") + "0123456789")
put("nrrd", "lying-gzip.nrrd", NRRD.format(type="uchar", dimension=3, sizes="2000 2000 2000", encoding="gzip", extra="").encode()
    + __import__("gzip").compress(b"\x01" * 64))
put("nrrd", "sizes-2p40.nrrd", NRRD.format(type="uchar", dimension=3, sizes="1099511627776 1 1", encoding="raw", extra="") + "x")
put("nrrd", "sizes-count.nrrd", NRRD.format(type="uchar", dimension=3, sizes="2 2", encoding="raw", extra="") + "x" * 4)
put("nrrd", "unknown-type.nrrd", NRRD.format(type="quaternion", dimension=3, sizes="2 2 2", encoding="raw", extra="") + "x" * 8)
put("nrrd", "bzip2.nrrd", NRRD.format(type="uchar", dimension=3, sizes="2 2 2", encoding="bzip2", extra="") + "x" * 8)
put("nrrd", "no-endian.nrrd", NRRD.format(type="int", dimension=3, sizes="2 2 2", encoding="raw", extra="") + "x" * 32)
put("nrrd", "missing-data-file.nrrd", NRRD.format(type="uchar", dimension=3, sizes="2 2 2", encoding="raw",
                                                  extra="data file: no-such-file.raw\n"))
put("nrrd", "data-file-list.nrrd", NRRD.format(type="uchar", dimension=3, sizes="2 2 2", encoding="raw", extra="data file: LIST\n"))
put("nrrd", "bad-magic.nrrd", "NRRD9\ntype: uchar\n\n")
put("nrrd", "time-series.nrrd", NRRD.format(type="uchar", dimension=4, sizes="2 2 2 3", encoding="raw", extra="") + "x" * 24)

# ---- MetaImage
MHA = "ObjectType = Image\nNDims = {ndims}\nDimSize = {sizes}\nElementType = {type}\n{extra}ElementDataFile = {data}\n"
put("metaimage", "truncated.mha", MHA.format(ndims=3, sizes="10 10 10", type="MET_USHORT", extra="", data="LOCAL") + "\x00" * 100)
put("metaimage", "zlib-bomb.mha", MHA.format(ndims=3, sizes="1000 1000 1000", type="MET_UCHAR", extra="CompressedData = True\n",
                                             data="LOCAL").encode() + zlib.compress(b"\x00" * 64))
put("metaimage", "missing-data-file.mha", MHA.format(ndims=3, sizes="2 2 2", type="MET_UCHAR", extra="", data="gone.raw"))
put("metaimage", "vector-type.mha", MHA.format(ndims=3, sizes="2 2 2", type="MET_UCHAR_ARRAY", extra="", data="LOCAL") + "x" * 8)
put("metaimage", "channels-3.mha", MHA.format(ndims=3, sizes="2 2 2", type="MET_UCHAR", extra="ElementNumberOfChannels = 3\n",
                                              data="LOCAL") + "x" * 24)
put("metaimage", "ascii-data.mha", MHA.format(ndims=3, sizes="2 2 2", type="MET_UCHAR", extra="BinaryData = False\n",
                                              data="LOCAL") + "1 2 3 4 5 6 7 8\n")
put("metaimage", "no-data-file-line.mha", "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\n")
put("metaimage", "dims-2p40.mha", MHA.format(ndims=3, sizes="1099511627776 1 1", type="MET_UCHAR", extra="", data="LOCAL") + "x")

# ---- NumPy .npy
def npy(header_dict, payload=b""):
    text = header_dict.encode()
    text += b" " * ((64 - (10 + len(text) + 1) % 64) % 64) + b"\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(text)) + text + payload


put("npy", "truncated.npy", npy("{'descr': '<f8', 'fortran_order': False, 'shape': (100, 100, 100), }", b"\x00" * 64))
put("npy", "shape-2p40.npy", npy("{'descr': '|u1', 'fortran_order': False, 'shape': (1099511627776, 1, 1), }", b"\x00"))
put("npy", "structured.npy", npy("{'descr': [('a', '<i4')], 'fortran_order': False, 'shape': (2, 2, 2), }", b"\x00" * 32))
put("npy", "complex.npy", npy("{'descr': '<c16', 'fortran_order': False, 'shape': (2, 2, 2), }", b"\x00" * 128))
put("npy", "four-d.npy", npy("{'descr': '|u1', 'fortran_order': False, 'shape': (2, 2, 2, 3), }", b"\x00" * 24))
put("npy", "header-length-lies.npy", b"\x93NUMPY\x01\x00\xff\xff{'descr': '|u1'")

# ---- VTK meshes
put("vtk", "points-2p31.vtk", "# vtk DataFile Version 4.2\nx\nBINARY\nDATASET POLYDATA\nPOINTS 2147483647 double\n" + "\x00" * 24)
put("vtk", "index-out-of-range.vtk", "# vtk DataFile Version 4.2\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
    "POLYGONS 1 4\n3 0 1 7\n")
put("vtk", "not-polydata.vtk", "# vtk DataFile Version 4.2\nx\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n")
put("vtk", "strips.vtk", "# vtk DataFile Version 4.2\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
    "TRIANGLE_STRIPS 1 4\n3 0 1 2\n")
put("vtp", "array-size-2p64.vtp", "<VTKFile type=\"PolyData\" header_type=\"UInt64\"><PolyData><Piece NumberOfPoints=\"1\" "
    "NumberOfPolys=\"0\"><Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"binary\">//////////8="
    "</DataArray></Points></Piece></PolyData></VTKFile>")
put("vtp", "unstructured-grid.vtp", "<?xml version=\"1.0\"?><VTKFile type=\"UnstructuredGrid\"></VTKFile>")
put("vtp", "offset-beyond-appended.vtp", "<VTKFile type=\"PolyData\"><PolyData><Piece NumberOfPoints=\"1\" NumberOfPolys=\"0\">"
    "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"999999\"/></Points></Piece>"
    "</PolyData><AppendedData encoding=\"raw\">_abc</AppendedData></VTKFile>")

# ---- geometry fields ITK must not see (ITK 5.2 aborts the process on a NaN in a NIfTI sform;
# fuzz/regressions/nifti/crash-nan-sform-itk-abort.nii is the fuzzer's original input)
def with_srow(header, values):
    header = bytearray(header)
    struct.pack_into("<h", header, 254, 2)  # sform_code
    struct.pack_into("<12f", header, 280, *values)
    return bytes(header)


put("nifti", "nan-sform.nii", with_srow(nifti1((2, 2, 2)), [float("nan"), 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]) + b"\x01" * 8)
put("nifti", "zero-sform-column.nii", with_srow(nifti1((2, 2, 2)), [0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]) + b"\x01" * 8)
put("nrrd", "nan-space-directions.nrrd", NRRD.format(type="uchar", dimension=3, sizes="2 2 2", encoding="raw",
    extra="space: left-posterior-superior\nspace directions: (nan,0,0) (0,1,0) (0,0,1)\n") + "x" * 8)
put("metaimage", "inf-offset.mha", MHA.format(ndims=3, sizes="2 2 2", type="MET_UCHAR", extra="Offset = inf 0 0\n", data="LOCAL")
    + "x" * 8)
put("metaimage", "spacing-count.mha", MHA.format(ndims=3, sizes="1 1 1", type="MET_UCHAR", extra="ElementSpacing = 1 1\n",
                                                 data="LOCAL") + "\x01")
