#include "digitize_command.hpp"

#include <cstdio>
#include <iostream>

#include "dsreg/text.hpp"
#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "dsreg/volume_io.hpp"
#include "dsreg/output_paths.hpp"
#include "dsreg/pipeline.hpp"

namespace dsreg::cli {

namespace {

struct DigitizeOptions {
    VolumeSource source;
    std::string output;
};

void run(const DigitizeOptions& o) {
    if (o.source.shape.empty()) throw Error("digitize needs --shape");
    if (file_extension(o.output) != "vol") throw Error("-o " + o.output + ": digitize writes a DGtal .vol file (use .vol)");
    check_output_folder("-o", o.output);
    const LoadedVolume loaded = load_volume(o.source);
    const VoxelGrid& g = loaded.volume.grid;
    write_vol(o.output, g.dims, loaded.volume.mask);
    // A .vol file has no spacing or origin: print them, so the voxels can be placed as dsreg does.
    const auto triple = [](const Eigen::Vector3d& v) {
        return format("%.17g", v.x()) + "," + format("%.17g", v.y()) + "," + format("%.17g", v.z());
    };
    std::cout << "dims " << g.dims[0] << "," << g.dims[1] << "," << g.dims[2] << " spacing " << triple(g.spacing)
              << " origin " << triple(g.origin) << '\n';
}

}  // namespace

void add_digitize_command(CLI::App& app) {
    auto options = std::make_shared<DigitizeOptions>();
    CLI::App* cmd = app.add_subcommand(
        "digitize", "Write the Gauss digitization of a --shape as a .vol file (value 1 inside, 0 outside); prints the "
                    "grid's dims, spacing and origin, which a .vol file does not hold");
    cmd->add_option("--shape", options->source.shape,
                    "Named shape or polynomial in x, y, z (F <= 0 inside), as for regularize")
        ->required();
    cmd->add_option("--h", options->source.h, "Grid step, physical units (default: 1/64 of the shape's extent)");
    cmd->add_option("--box", options->source.box, "Half-size of the domain of a polynomial --shape")->capture_default_str();
    cmd->add_option("-o,--output", options->output, "Output volume (.vol)")->required();
    cmd->callback([options] { run(*options); });
}

}  // namespace dsreg::cli
