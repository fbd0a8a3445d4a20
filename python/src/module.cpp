// dsreg Python module `dsreg._dsreg`: the thin C++ layer under python/dsreg/__init__.py.
//
// Every job goes through the library's one entry point (run_pipeline, load_volume,
// run_evaluation, read_mesh, write_mesh) with its options parsed by the command line's own flag
// definitions (apps/regularize_command.hpp, apps/eval_command.hpp): the Python layer turns
// keyword options into flags ("ii_kernel='ball'" → "--ii-kernel=ball"). The GIL is released
// while the library works; progress events come back on the calling thread, where they check
// for Ctrl-C and call the user's progress function.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "dsreg/error.hpp"
#include "dsreg/evaluation_report.hpp"
#include "dsreg/grid_placement.hpp"
#include "dsreg/mesh_io.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/progress.hpp"
#include "dsreg/world_space.hpp"
#include "eval_command.hpp"
#include "numpy_arrays.hpp"
#include "regularize_command.hpp"

namespace py = pybind11;

namespace dsreg::python {

namespace {

using IndexMatrix = Eigen::Matrix<std::int64_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// ---------------------------------------------------------------------------------------------
// Flags

/// (name without "--", number of values (0 for a switch such as --clamp, -1 for a list of any
/// length such as --labels 1,4,7), type, default, help) of every named flag of `app`, in the
/// order of `--help`.
py::list flag_table(const CLI::App& app) {
    py::list table;
    for (const CLI::Option* option : app.get_options()) {
        if (option->get_lnames().empty()) continue;
        const int values = option->get_items_expected_max();
        table.append(py::make_tuple(option->get_lnames().front(), values >= CLI::detail::expected_max_vector_size ? -1 : values,
                                    option->get_type_name(), option->get_default_str(), option->get_description()));
    }
    return table;
}

/// Parses `args` (e.g. {"--radius=3", "--clamp"}) with the flags registered on `app`.
void parse_flags(CLI::App& app, const std::vector<std::string>& args) {
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them last first
    app.parse(reversed);
}

struct Regularize {
    CLI::App app;
    cli::RegularizeCommand command;
    Regularize() {
        app.set_help_flag();
        cli::add_pipeline_flags(app, command);
    }
    /// Parses the flags and applies them to the library's option structs.
    void parse(const std::vector<std::string>& args) {
        parse_flags(app, args);
        cli::apply_flags(command);
    }
};

struct Evaluate {
    CLI::App app;
    EvaluationRequest request;
    Evaluate() {
        app.set_help_flag();
        cli::add_evaluation_flags(app, request);
    }
};

// ---------------------------------------------------------------------------------------------
// Meshes

IndexMatrix index_matrix(const FaceMatrix& faces) { return faces.cast<std::int64_t>(); }

py::dict mesh_dict(PolygonMesh&& mesh) {
    py::dict scalars;
    for (auto& [name, values] : mesh.vertex_scalars) scalars[py::str(name)] = py::cast(std::move(values));
    py::dict d;
    d["vertices"] = py::cast(std::move(mesh.vertices));
    d["faces"] = py::cast(index_matrix(mesh.faces));
    d["face_normals"] = py::cast(std::move(mesh.face_normals));
    d["vertex_scalars"] = scalars;
    d["coordinate_system"] = mesh.coordinate_system;
    py::dict integers;  // e.g. inner_label, outer_label of a label complex
    for (auto& [name, values] : mesh.face_integers) integers[py::str(name)] = py::cast(std::move(values));
    d["face_integers"] = integers;
    return d;
}

using FaceIntegers = std::vector<std::pair<std::string, Eigen::VectorXi>>;

PolygonMesh polygon_mesh(PointMatrix vertices, FaceMatrix faces, PointMatrix face_normals,
                         std::vector<std::pair<std::string, Eigen::VectorXd>> vertex_scalars,
                         std::string coordinate_system = "", FaceIntegers face_integers = {}) {
    for (const auto& [name, values] : face_integers)
        if (values.size() != faces.rows())
            throw Error("face integers " + name + ": " + std::to_string(faces.rows()) + " values are needed (got " +
                        std::to_string(values.size()) + ")");
    return PolygonMesh{std::move(vertices), std::move(faces), std::move(face_normals), std::move(vertex_scalars),
                       std::move(coordinate_system), std::move(face_integers)};
}

// ---------------------------------------------------------------------------------------------
// Progress and interruption

/// The progress callback of one call: on the calling thread, with the GIL, it lets Python
/// handle pending signals (Ctrl-C raises KeyboardInterrupt there) and calls the user's
/// progress(stage, fraction); a Python exception from either is kept and the library is
/// stopped with dsreg::Interrupted, then the exception is raised again once the library has
/// unwound.
class Interruption {
public:
    explicit Interruption(py::object progress) : progress_(std::move(progress)) {}

    ProgressCallback callback() {
        return [this](const ProgressEvent& event) {
            py::gil_scoped_acquire gil;
            try {
                if (PyErr_CheckSignals() != 0) throw py::error_already_set();
                if (!progress_.is_none()) progress_(event.stage, event.fraction);
            } catch (py::error_already_set& error) {
                pending_.emplace(std::move(error));
                throw Interrupted();
            }
        };
    }

    /// After the library threw Interrupted, with the GIL: the Python exception that stopped it.
    [[noreturn]] void raise() {
        if (pending_) {
            pending_->restore();
            pending_.reset();
        } else {
            PyErr_SetNone(PyExc_KeyboardInterrupt);
        }
        throw py::error_already_set();
    }

private:
    py::object progress_;
    std::optional<py::error_already_set> pending_;
};

// ---------------------------------------------------------------------------------------------
// Jobs

/// `input`: a numpy array, a path (str) or None (with --shape among the flags).
py::dict regularize(const py::object& input, const std::vector<std::string>& args,
                    const std::optional<Eigen::Matrix4d>& affine, const std::string& affine_space,
                    const std::optional<Eigen::Vector3d>& spacing, const std::optional<Eigen::Vector3d>& origin,
                    const py::object& progress) {
    Regularize job;
    job.parse(args);
    VolumeSource& source = job.command.source;
    std::optional<py::array> values;  // keeps the array alive and unchanged in size while dsreg reads it
    if (py::isinstance<py::str>(input)) {
        source.input_path = input.cast<std::string>();
    } else if (!input.is_none()) {
        values = py::reinterpret_borrow<py::array>(input);
        source.array = voxel_array_of(*values, "mask");
    }
    source.affine = affine;
    source.affine_space = parse_output_space(affine_space);
    if (source.affine_space == OutputSpace::Voxel) throw Error("affine_space: lps or ras (the world the affine maps to), not voxel");
    if (spacing) source.spacing = spacing;
    source.origin = origin;
    const PipelineOptions& options = job.command.options;
    const PipelineOutputs& outputs = job.command.outputs;  // files of --report, --html, ... if asked
    check_pipeline_options(options, !source.shape.empty());
    check_pipeline_outputs(outputs);

    Interruption interruption(progress);
    std::string report;
    PolygonMesh mesh;
    std::vector<std::pair<std::int64_t, PolygonMesh>> label_meshes;  // of a label map: (value, closed surface)
    try {
        py::gil_scoped_release release;
        PipelineResult result = run_pipeline(source, options, interruption.callback());
        if (outputs.any()) write_pipeline_outputs(result, options, outputs, source, interruption.callback());
        mesh = output_mesh(result, outputs);
        for (std::size_t i = 0; i < result.label_meshes.size(); ++i)
            label_meshes.emplace_back(result.surface.label_values[result.label_meshes[i].label],
                                      output_label_mesh(result, outputs, i));
        report = pipeline_report(result, options, outputs, source).dump();
    } catch (const Interrupted&) {
        interruption.raise();
    }
    py::dict d = mesh_dict(std::move(mesh));
    d["report"] = report;
    py::list labels;
    for (auto& [value, label_mesh] : label_meshes) labels.append(py::make_tuple(value, mesh_dict(std::move(label_mesh))));
    d["label_meshes"] = labels;
    return d;
}

/// (values float32 [i, j, k], voxel-to---space affine) of a volume file.
py::tuple read_volume(const std::string& path, const std::vector<std::string>& args,
                      const std::optional<Eigen::Vector3d>& spacing) {
    Regularize job;
    job.parse(args);
    VolumeSource& source = job.command.source;
    source.input_path = path;
    if (spacing) source.spacing = spacing;
    ScalarVolume volume;
    {
        py::gil_scoped_release release;
        volume = load_volume_values(source);
    }
    const Eigen::Matrix4d affine = grid_affine(volume.grid, job.command.outputs.space);
    return py::make_tuple(fortran_array(std::move(volume.values), volume.grid.dims, py::dtype::of<float>()), affine);
}

/// (mask bool [i, j, k], affine) of a shape digitized as --shape does it (flags --shape, --h, --box, ...).
py::tuple digitize(const std::vector<std::string>& args) {
    Regularize job;
    job.parse(args);
    LoadedVolume loaded;
    {
        py::gil_scoped_release release;
        loaded = load_volume(job.command.source);
    }
    const Eigen::Matrix4d affine = grid_affine(loaded.volume.grid);
    return py::make_tuple(fortran_array(std::move(loaded.volume.mask), loaded.volume.grid.dims, py::dtype("bool")),
                          affine);
}

/// The `dsreg eval --json` object (as JSON text) of a mesh (with its face field, if any: the
/// folded faces) against the flags' shape or volume.
std::string evaluate(PointMatrix vertices, FaceMatrix faces, PointMatrix face_normals, const std::vector<std::string>& args) {
    Evaluate job;
    parse_flags(job.app, args);
    const PolygonMesh mesh = polygon_mesh(std::move(vertices), std::move(faces), std::move(face_normals), {});
    py::gil_scoped_release release;
    const EvaluationRun run = run_evaluation(mesh, "mesh", job.request);
    return evaluation_report(run, "").dump();
}

py::dict read_mesh_file(const std::string& path) {
    PolygonMesh mesh;
    {
        py::gil_scoped_release release;
        mesh = read_mesh(path);
    }
    return mesh_dict(std::move(mesh));
}

void write_mesh_file(const std::string& path, PointMatrix vertices, FaceMatrix faces, PointMatrix face_normals,
                     std::vector<std::pair<std::string, Eigen::VectorXd>> vertex_scalars,
                     const std::string& coordinate_system, FaceIntegers face_integers) {
    const PolygonMesh mesh = polygon_mesh(std::move(vertices), std::move(faces), std::move(face_normals),
                                          std::move(vertex_scalars), coordinate_system, std::move(face_integers));
    py::gil_scoped_release release;
    write_mesh(path, mesh);
}

py::dict triangulate(PointMatrix vertices, FaceMatrix faces, PointMatrix face_normals,
                     std::vector<std::pair<std::string, Eigen::VectorXd>> vertex_scalars, FaceIntegers face_integers) {
    PolygonMesh mesh = polygon_mesh(std::move(vertices), std::move(faces), std::move(face_normals),
                                    std::move(vertex_scalars), "", std::move(face_integers));
    {
        py::gil_scoped_release release;
        mesh = triangulate_shorter_diagonal(mesh);
    }
    return mesh_dict(std::move(mesh));
}

/// dsreg::FileError → OSError (with its errno: FileNotFoundError, PermissionError, ...);
/// dsreg::Error and flag errors → ValueError, with the command line's message.
void translate_errors(std::exception_ptr error) {
    try {
        if (error) std::rethrow_exception(error);
    } catch (const FileError& e) {
        if (e.error_number() != 0)
            PyErr_SetObject(PyExc_OSError, py::make_tuple(e.error_number(), e.what()).ptr());
        else
            PyErr_SetString(PyExc_OSError, e.what());
    } catch (const Error& e) {
        PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const CLI::ParseError& e) {
        PyErr_SetString(PyExc_ValueError, e.what());
    }
}

}  // namespace

}  // namespace dsreg::python

PYBIND11_MODULE(_dsreg, m) {
    using namespace dsreg::python;
    m.doc() = "dsreg's C++ core; use the dsreg package, which documents every function.";
    m.attr("__version__") = DSREG_VERSION;
    py::register_exception_translator(&translate_errors);
    m.def("regularize_flags", [] { return flag_table(Regularize().app); });
    m.def("evaluation_flags", [] { return flag_table(Evaluate().app); });
    m.def("regularize", &regularize, py::arg("input"), py::arg("args"), py::arg("affine"), py::arg("affine_space"),
          py::arg("spacing"), py::arg("origin"), py::arg("progress"));
    m.def("read_volume", &read_volume, py::arg("path"), py::arg("args"), py::arg("spacing"));
    m.def("digitize", &digitize, py::arg("args"));
    m.def("evaluate", &evaluate, py::arg("vertices"), py::arg("faces"), py::arg("face_normals"), py::arg("args"));
    m.def("read_mesh", &read_mesh_file, py::arg("path"));
    m.def("write_mesh", &write_mesh_file, py::arg("path"), py::arg("vertices"), py::arg("faces"),
          py::arg("face_normals"), py::arg("vertex_scalars"), py::arg("coordinate_system"), py::arg("face_integers"));
    m.def("triangulate", &triangulate, py::arg("vertices"), py::arg("faces"), py::arg("face_normals"),
          py::arg("vertex_scalars"), py::arg("face_integers"));
}
