"""dsreg: smooth quad meshes from 3-D binary images and label maps.

Digital surface regularization by normal vector field alignment (Coeurjolly, Gueth, Lachaud,
DGCI 2017): the boundary of the object (every voxel face between object and background) is made a
closed 2-manifold, a normal vector is estimated on each face, and the vertices are moved by one
sparse convex solve so that every quad lines up with its normal, stays close to the data and is
well shaped. This package is the C++ library behind the ``dsreg`` command, on numpy arrays.

Conventions
-----------
- A volume is a 3-D array indexed ``[i, j, k]`` with i along x, j along y, k along z (nibabel's
  convention: ``nibabel.load(f).get_fdata()`` and ``img.affine`` can be passed as they are, with
  ``affine_space="ras"``).
- Voxel (i, j, k) is centred at ``affine @ (i, j, k, 1)``; without an affine, at
  ``origin + spacing * (i, j, k)``. An affine maps to LPS (ITK, SimpleITK, DICOM, 3D Slicer, and
  what read_volume returns) unless ``affine_space="ras"`` (nibabel). Mesh vertices are voxel
  corners moved by the regularization, in the affine's space by default, or in ``space=`` (lps,
  ras, voxel: the command line's --space).
- Faces are counter-clockwise seen from outside.
- Keyword options are the command line's flags: ``--ii-kernel ball`` is ``ii_kernel="ball"``.
- Bad arguments or content raise ValueError with the command line's message; files that cannot
  be opened or written raise OSError.

Functions: regularize, read_volume, digitize, evaluate, read_mesh; class Mesh.
"""

import json as _json
import os as _os


def _load_core():
    """Imports the C++ module with OpenMP's passive wait policy, as the dsreg command runs.

    GCC's OpenMP threads otherwise spin between parallel loops, taking the cores from the threads
    doing the work whenever anything else runs on the machine (docs/python.md). The runtime reads
    OMP_WAIT_POLICY once, when it is loaded with this module, so the variable is set only for
    that moment (child processes and the caller's environment are left as they were) and only if
    the user has not chosen a policy and no OpenMP runtime is loaded yet.
    """
    if "OMP_WAIT_POLICY" in _os.environ or _openmp_loaded():
        from . import _dsreg
        return _dsreg
    _os.environ["OMP_WAIT_POLICY"] = "passive"
    try:
        from . import _dsreg
    finally:
        del _os.environ["OMP_WAIT_POLICY"]
    return _dsreg


def _openmp_loaded() -> bool:
    try:
        with open("/proc/self/maps") as maps:
            return any("libgomp" in line for line in maps)
    except OSError:
        return False


_dsreg = _load_core()

import numpy as _np  # noqa: E402

from ._flags import flag_arguments as _flag_arguments  # noqa: E402
from ._flags import flag_table as _flag_table  # noqa: E402
from ._flags import keyword_docs as _keyword_docs  # noqa: E402
from ._mesh import Mesh  # noqa: E402

Mesh.__module__ = __name__  # shown as dsreg.Mesh

__all__ = ["Mesh", "regularize", "read_volume", "digitize", "evaluate", "read_mesh", "regularize_keywords"]
__version__ = _dsreg.__version__

_REGULARIZE_FLAGS = _flag_table(_dsreg.regularize_flags())
_EVALUATION_FLAGS = _flag_table(_dsreg.evaluation_flags())

#: The flags of ``dsreg regularize`` that are not keyword options of regularize(), and why.
EXCLUDED_REGULARIZE_FLAGS = {
    "help": "help(dsreg.regularize)",
    "output": "regularize() returns the Mesh; Mesh.write(path) writes it",
    "spacing": "spacing= is an argument of its own (with origin= and affine=)",
    "quiet": "nothing is printed; progress= receives the stages",
    "verbose": "nothing is printed; progress= receives the stages",
    "progress": "progress= is an argument of its own (a callable: the stages and the solver's iterations)",
    # Block-wise streaming (docs/scaling.md) reads a volume file block by block, for volumes
    # larger than memory: the command line's (dsreg regularize --block-size, dsreg-mpi).
    "block-size": "block-wise streaming of a file larger than memory: dsreg regularize --block-size",
    "block-halo": "a flag of block-wise streaming (dsreg regularize --block-size)",
    "schwarz-sweeps": "a flag of block-wise streaming (dsreg regularize --block-size)",
    "coarse-spacing": "a flag of block-wise streaming (dsreg regularize --block-size)",
    "coarse-space": "a flag of block-wise streaming (dsreg regularize --block-size)",
    "fragments": "a flag of block-wise streaming (dsreg regularize --block-size)",
}

#: The flags of ``dsreg eval`` that are not keyword options of evaluate(), and why.
EXCLUDED_EVALUATION_FLAGS = {
    "help": "help(dsreg.evaluate)",
    "shape": "shape is an argument of its own",
    "h": "h is an argument of its own",
    "json": "evaluate() returns the JSON content as a dict",
}

_VOLUME_KEYWORDS = ("space", "raw_dims", "raw_type", "raw_big_endian", "raw_header_bytes", "max_voxels", "max_memory")
_DIGITIZE_KEYWORDS = ("box", "max_voxels", "max_memory")


def regularize_keywords():
    """The keyword options of regularize(): the flags of ``dsreg regularize`` (with ``_`` for
    ``-``) less EXCLUDED_REGULARIZE_FLAGS."""
    return [k for k, f in _REGULARIZE_FLAGS.items() if f.name not in EXCLUDED_REGULARIZE_FLAGS]


def _vector3(name: str, values):
    if values is None:
        return None
    array = _np.asarray(values, dtype=_np.float64)
    if array.ndim == 0:
        array = _np.full(3, float(array))
    if array.shape != (3,):
        raise ValueError(f"{name}: three values (x, y, z) are needed (got shape {array.shape})")
    return array


def _affine(values):
    if values is None:
        return None
    array = _np.asarray(values, dtype=_np.float64)
    if array.shape != (4, 4):
        raise ValueError(f"affine: a 4 x 4 voxel-to-world matrix is needed (got shape {array.shape})")
    return array


def _volume_input(mask):
    """None, a path (str) or a numpy array (without copying an array)."""
    if mask is None or isinstance(mask, str):
        return mask
    if isinstance(mask, _os.PathLike):
        return _os.fspath(mask)
    return _np.asarray(mask)


def regularize(mask, *, affine=None, affine_space="lps", spacing=None, origin=None, progress=None, **options) -> Mesh:
    """The regularized boundary mesh of the object of a 3-D volume.

    Parameters
    ----------
    mask : array_like (3-D), str or os.PathLike, or None
        The volume, indexed ``[i, j, k]`` with i along x (nibabel's convention), of any memory
        order and strides: bool, any integer or float dtype (float16 to float64), either byte
        order. The object is the voxels with value > 0, or equal to ``label=`` (one label of a
        label map), or with ``min <= value <= max`` when ``min=`` or ``max=`` is given (the
        command line's --label, --min, --max). The array is read in
        place and thresholded into one 1-byte mask: it is not copied otherwise, and must not be
        changed by another thread during the call.
        A path instead reads a volume file as ``dsreg regularize FILE`` does (any format it
        reads: NIfTI, NRRD, MetaImage, TIFF, HDF5, VTK, DICOM, .npy, .vol, .longvol, .pgm3d,
        .raw with ``raw_dims=`` etc.). None with ``shape=`` digitizes an implicit
        shape as ``dsreg regularize --shape`` does (``h=``, ``box=``).
        With ``multi_label=True`` (or ``labels=[1, 4, 7]``, which keeps those and turns the
        other labels into background) the array is a label map: every distinct non-zero value
        is a label, any integer dtype (or floats holding integers; 2.5 or NaN raises ValueError
        naming the voxel), any strides, placed by ``affine``/``spacing``/``origin`` as a mask
        is; all the interfaces are regularized at once (the command line's --multi-label,
        docs/multi-label.md).
    affine : array_like (4, 4), optional
        Voxel-to-world matrix of the array: voxel (i, j, k) is centred at
        ``affine @ (i, j, k, 1)`` in ``affine_space``. Its columns may be oblique or mirrored but
        must be perpendicular (within 1e-3, as the file readers accept direction cosines). By
        default the vertices come out in this world. Not with spacing or origin.
    affine_space : {"lps", "ras"}
        The world the affine maps to: "lps" (default: read_volume's affine, ITK, SimpleITK,
        DICOM) or "ras" (nibabel's ``img.affine``). It is also the default of ``space=``, so
        that the vertices come in the affine's space and ``Mesh.coordinate_system`` names it.
    spacing : float or array_like (3,), optional
        Voxel size along i, j, k in physical units (default 1; for a file, overrides the file's
        as --spacing does).
    origin : array_like (3,), optional
        Position of the centre of voxel (0, 0, 0) (default 0).
    progress : callable(stage: str, fraction: float), optional
        Called as each stage starts (fraction 0) and ends (fraction 1): "read" (thresholding an
        array, reading a file) or "digitize", "surface", "normals", "at", "regularize",
        "validity" (for a label map "labels" instead: each label's surface); inside "regularize", an iterative solver also reports each iteration as
        stage "solve" (fraction: the share of the way to its stop, log scale). It runs on the
        calling thread; an exception it raises stops the work and propagates (inside the solve:
        at that iteration).
    **options
        The command line's flags, ``-`` written ``_`` (listed below): values are written as the
        flag's text and checked by the command line's parser (``raw_dims=(4, 5, 6)`` is
        ``--raw-dims 4,5,6``; a switch such as ``clamp=True`` is ``--clamp``; None leaves the
        default). Lengths (radius, h, box) are in physical units. The flags that write files
        (``report=``, ``html=``, ``input_mesh=``, ``export_normals=``, ``features=``) write them
        as the command line does, after the run (a "write" stage). ``space=`` ("lps", "ras" or
        "voxel", the command line's --space) chooses the coordinates of the vertices: the same
        mesh as ``dsreg regularize FILE --space S`` for ``regularize(*read_volume(FILE),
        space=S)`` (read_volume returns an LPS affine) or ``regularize(FILE, space=S)``.

    Returns
    -------
    Mesh
        vertices (n, 3) float64, faces (m, 4) int64 counter-clockwise seen from outside (with
        ``triangulate=True``, (2m, 3) triangles split along the shorter diagonal),
        face_normals (the normal field u), vertex_scalars (``"v"`` with ``normals="at"``), report
        (the command line's ``--report`` content). Of a label map: the complex, every interface
        face once, with ``face_labels`` (m, 2) int64, the label values (inner, outer) on its two
        sides (0: background; the normal points from inner to outer), and ``label_meshes``
        {label value: Mesh}, each label's closed outward surface with the complex's vertex
        positions bit for bit and its line of ``report["labels"]`` as its report.

    Raises
    ------
    ValueError
        Bad arguments or content (an empty object, a 2-D array, NaN spacing, an unknown
        --normals ...), with the command line's message.
    OSError
        A file that cannot be read.
    KeyboardInterrupt
        Ctrl-C: the work stops at the next stage boundary.

    Notes
    -----
    The GIL is released while dsreg works (other Python threads run); dsreg itself uses
    OpenMP's threads, as many as the command line (OMP_NUM_THREADS).

    Examples
    --------
    >>> img = nibabel.load("seg.nii.gz")
    >>> mesh = dsreg.regularize(img.get_fdata(), label=3, affine=img.affine, affine_space="ras", radius=4.0)
    >>> mesh.write("structure3.vtk")  # RAS vertices, tagged SPACE=RAS for 3D Slicer
    """
    if options.get("space") is None and affine is not None:
        options["space"] = affine_space  # the vertices come in the affine's space
    args = _flag_arguments("regularize", _REGULARIZE_FLAGS, options, excluded=EXCLUDED_REGULARIZE_FLAGS)
    if progress is not None and not callable(progress):
        raise TypeError(f"progress= takes a callable (stage, fraction), not {type(progress).__name__}")
    arrays = _dsreg.regularize(
        _volume_input(mask),
        args,
        _affine(affine),
        str(affine_space),
        _vector3("spacing", spacing),
        _vector3("origin", origin),
        progress,
    )
    mesh = Mesh._from_arrays(arrays, _json.loads(arrays["report"]))
    for entry in mesh.report.get("labels", []):  # each label's own line of the report
        mesh.label_meshes[entry["label"]].report = dict(entry)
    return mesh


regularize.__doc__ += (
    "\n    Keyword options\n    ---------------\n" + _keyword_docs(_REGULARIZE_FLAGS, regularize_keywords()) + "\n"
)


def read_volume(path, *, spacing=None, **options):
    """The voxel values of a volume file, as the command line reads it.

    Parameters
    ----------
    path : str or os.PathLike
        Any format ``dsreg regularize`` reads, through the same readers: NIfTI-1/2 (.nii,
        .nii.gz, .hdr/.img), NRRD (.nrrd, .nhdr), MetaImage (.mha, .mhd), TIFF, HDF5 (.h5),
        VTK images (.vtk), DICOM (a folder holding one series, or a .dcm file), NumPy .npy,
        DGtal's .vol, .longvol, .pgm3d, and .raw (with ``raw_dims=``...).
    spacing : float or array_like (3,), optional
        Overrides the file's voxel size (--spacing).
    **options
        space ("lps", the default, "ras" or "voxel": the space the affine maps to, as the
        command line's --space), raw_dims, raw_type, raw_big_endian, raw_header_bytes (the
        layout of a .raw file), max_voxels, max_memory: the command line's flags.

    Returns
    -------
    values : numpy.ndarray, float32, shape (nx, ny, nz)
        Indexed ``[i, j, k]`` with i along x; Fortran order (x fastest, as in the file and in
        dsreg's mask, so that regularize reads it in order). Integers up to 2^24 are exact.
    affine : numpy.ndarray, (4, 4) float64
        Voxel-to-world matrix: voxel (i, j, k) is centred at ``affine @ (i, j, k, 1)`` in LPS
        (origin + direction @ (spacing * (i, j, k)) with the file's direction cosines, as ITK
        reads them; the identity direction for the DGtal formats, .raw and .npy), in RAS with
        ``space="ras"`` (nibabel's ``img.affine`` of a NIfTI file), or the identity with
        ``space="voxel"``. ``regularize(values, affine=affine)`` then meshes the file as the
        command line does (pass ``affine_space="ras"`` with a RAS affine).
    """
    args = _flag_arguments("read_volume", _REGULARIZE_FLAGS, options, allowed=_VOLUME_KEYWORDS)
    return _dsreg.read_volume(_os.fspath(path), args, _vector3("spacing", spacing))


def digitize(shape: str, h=None, **options):
    """The Gauss digitization of an implicit shape, as ``dsreg regularize --shape`` makes it.

    Parameters
    ----------
    shape : str
        A named shape (sphere1 sphere9 ellipsoid cylinder torus rcube goursat goursat-hole
        distel leopold diabolo heart crixxi) or a polynomial in x, y, z such as
        ``"x^2+y^2+z^2-25"``; the inside is F <= 0.
    h : float, optional
        Grid step in physical units (default 1/64 of the largest side of the shape's box).
    **options
        box (half-size of the domain [-box, box]^3 of a polynomial, default 10), max_voxels,
        max_memory: the command line's flags.

    Returns
    -------
    mask : numpy.ndarray, bool, shape (nx, ny, nz)
        True inside: voxel (i, j, k) is inside iff F(affine @ (i, j, k, 1)) <= 0. Indexed
        ``[i, j, k]``, i along x, Fortran order.
    affine : numpy.ndarray, (4, 4) float64
        Voxel-to-world matrix: diag(h, h, h) and the position of voxel (0, 0, 0).

    ``regularize(mask, affine=affine)`` treats the mask as a file (default radius in voxels);
    ``regularize(None, shape=..., h=...)`` gives the shape's own defaults and ``normals="exact"``.
    """
    args = _flag_arguments("digitize", _REGULARIZE_FLAGS, options, allowed=_DIGITIZE_KEYWORDS)
    args = [f"--shape={shape}"] + ([f"--h={float(h)!r}"] if h is not None else []) + args
    return _dsreg.digitize(args)


def evaluate(mesh, shape: str = None, h=None, **options) -> dict:
    """Accuracy of a mesh against an implicit shape or a volume file: the ``dsreg eval --json`` content.

    Parameters
    ----------
    mesh : Mesh, str or os.PathLike
        Any triangle or quad mesh (a path is read with read_mesh), in the shape's frame (or, with
        voxel_coordinates=True, in the voxel frame of digitize(shape, h)). Its face_normals, if any
        (the field u of a regularized mesh), are the field the folded faces are counted against.
    shape : str, optional
        As for digitize, or "plane" (the tilted half-space n·p <= d in [-box, box]^3). Without
        it, volume= gives the truth.
    h : float, optional
        Grid step: distances are also given in units of h ("vertex_distance_h"), and the voxel
        classification uses digitize(shape, h) (default 1/64 of the shape's extent).
    **options
        box, plane_normal, plane_offset, wall_margin, volume_cells, voxel_coordinates,
        face_errors (a CSV path), volume (a volume file instead of shape), min, max: the flags of
        ``dsreg eval``.

    Returns
    -------
    dict
        vertex_distance and normal_angle_deg (mean, l2, linf, p95; physical units and degrees),
        mesh_volume, shape_volume, relative_volume_error, voxel_classification (all, object and
        boundary voxels), triangle_min_angle_deg, validity, counts; with volume=, only
        voxel_classification and validity.
    """
    if not isinstance(mesh, Mesh):
        mesh = read_mesh(mesh)
    args = _flag_arguments("evaluate", _EVALUATION_FLAGS, options, excluded=EXCLUDED_EVALUATION_FLAGS)
    args = (
        ([f"--shape={shape}"] if shape is not None else [])
        + ([f"--h={float(h)!r}"] if h is not None else [])
        + args
    )
    vertices, faces, face_normals, _ = mesh._arrays()
    return _json.loads(_dsreg.evaluate(vertices, faces, face_normals, args))


def read_mesh(path) -> Mesh:
    """A mesh file (.obj, .off, .ply, .stl, .vtk, .vtp; triangles and/or quads) as a Mesh.

    Files mixing triangles and quads come back as triangles (the quads split along their shorter
    diagonal). PLY face properties nx ny nz become face_normals, other vertex properties
    vertex_scalars (VTK: cell normals and point scalars); the face properties (cell data)
    inner_label and outer_label of a label complex become face_labels; coordinate_system is read where 3D
    Slicer writes it. Raises OSError if the file cannot be read, ValueError if it is malformed.
    """
    return Mesh._from_arrays(_dsreg.read_mesh(_os.fspath(path)))
