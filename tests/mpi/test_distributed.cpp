// The MPI pipeline (include/dsreg/distributed.hpp), run by CTest under mpirun with 1, 2 and 4
// ranks: the welded mesh equals the serial CHOLMOD solve within 1e-6 voxel, with the same faces,
// vertices and Euler characteristics, also where block boundaries run through split pointels
// and thin parts; errors reach every rank alike.
#include <gtest/gtest.h>

#include <filesystem>

#include "dsreg/block_pipeline.hpp"
#include "dsreg/distributed.hpp"
#include "dsreg/error.hpp"
#include "dsreg/mesh_validity.hpp"
#include "dsreg/volume_io.hpp"

namespace dsreg {
namespace {

int world_rank() {
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    return rank;
}

int world_size() {
    int size = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    return size;
}

/// On rank 0: the distributed solve against the serial pipeline's with CHOLMOD.
void expect_equal_to_serial(const VolumeSource& source, const PipelineOptions& options) {
    PipelineOptions distributed_options = options;
    distributed_options.max_error_voxels = 1e-7;
    // The solves are compared: the repair that follows them (tested below) is not continuous in
    // the solve, a 1e-9 voxel change can flip a borderline fold on a thin plate.
    distributed_options.validity = ValidityMode::Off;
    const PipelineResult distributed = run_distributed_pipeline(MPI_COMM_WORLD, source, distributed_options);
    if (world_rank() != 0) return;
    // The whole-volume run of the options block-wise runs can do (fixed radius, no thin-part
    // weights nor shrink correction: plan_block_run).
    PipelineOptions serial_options = plan_block_run(source, options, "dsreg-mpi").options;
    serial_options.solver = SolverKind::Cholmod;
    serial_options.validity = ValidityMode::Off;
    const PipelineResult serial = run_pipeline(source, serial_options);
    ASSERT_EQ(distributed.surface.face_count(), serial.surface.face_count());
    ASSERT_EQ(distributed.surface.vertex_count(), serial.surface.vertex_count());
    EXPECT_EQ(distributed.surface.quads, serial.surface.quads);
    EXPECT_EQ(distributed.surface.adjacent_face, serial.surface.adjacent_face);
    EXPECT_EQ(distributed.surface.split_pointel_count, serial.surface.split_pointel_count);
    EXPECT_EQ(component_euler_characteristics(distributed.surface), component_euler_characteristics(serial.surface));
    EXPECT_EQ(distributed.object_voxels, serial.object_voxels);
    EXPECT_EQ(distributed.field.normals, serial.field.normals);
    const double voxel = serial.grid.spacing.minCoeff();
    const PointMatrix difference = distributed.regularization.positions - serial.regularization.positions;
    EXPECT_LT(difference.rowwise().norm().maxCoeff() / voxel, 1e-6);
    EXPECT_LE(distributed.regularization.solve.error_bound / voxel, 1e-7);
    EXPECT_NEAR(distributed.regularization.energy_after.total(distributed.weights),
                serial.regularization.energy_after.total(serial.weights), 1e-9);
    EXPECT_EQ(distributed.extension_report["blocks"]["ranks"], world_size());
}

TEST(Distributed, GoursatEqualsTheSerialSolve) {
    VolumeSource source;
    source.shape = "goursat";
    source.h = 0.5;
    expect_equal_to_serial(source, PipelineOptions{});
}

/// A volume whose block boundaries (blocks_for_parts: x = 12 for 2 ranks, x = 12 and y = 10 for
/// 4) run through split pointels (voxels touching only at a corner or along an edge across
/// them) and thin parts (plates and a rod one voxel thick across them, plates on either side).
std::string write_thin_parts_volume() {
    const Index3 dims{24, 20, 16};
    std::vector<std::uint8_t> v(std::size_t(dims[0] * dims[1] * dims[2]), 0);
    const auto set = [&](std::int64_t i, std::int64_t j, std::int64_t k) { v[std::size_t(i + dims[0] * (j + dims[1] * k))] = 1; };
    set(11, 9, 3), set(12, 10, 4);                        // corner contact at pointel (12, 10, 4)
    set(11, 10, 6), set(12, 9, 7);                        // and at (12, 10, 7)
    for (std::int64_t k = 2; k < 6; ++k) set(11, 3, k), set(12, 4, k);  // edge contact along x = 12, y = 4
    for (std::int64_t k = 2; k < 6; ++k) set(5, 9, k), set(6, 10, k);   // along y = 10
    for (std::int64_t j = 2; j < 18; ++j)
        for (std::int64_t i = 3; i < 21; ++i) set(i, j, 12);  // plate z = 12, across both cuts
    for (std::int64_t j = 12; j < 18; ++j)
        for (std::int64_t k = 1; k < 10; ++k) set(11, j, k), set(12, j, k + 1);  // plates either side of x = 12
    for (std::int64_t i = 1; i < 23; ++i) set(i, 15, 14);  // rod across x = 12
    const std::string path = (std::filesystem::temp_directory_path() / "dsreg_mpi_thin_parts.vol").string();
    int error = 0;
    if (world_rank() == 0) {
        try {
            write_vol(path, dims, v, 3);
        } catch (const Error&) {
            error = 1;
        }
    }
    MPI_Bcast(&error, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (error) throw Error("cannot write the test volume " + path);
    return path;
}

TEST(Distributed, BlockBoundariesThroughSplitPointelsAndThinParts) {
    VolumeSource source;
    source.input_path = write_thin_parts_volume();
    for (const Connectivity c : {Connectivity::TwentySix, Connectivity::Six}) {
        PipelineOptions options;
        options.connectivity = c;
        options.normals.radius = 2.5;
        expect_equal_to_serial(source, options);
    }
}

TEST(Distributed, RepairsTheWeldedMeshIntoAValidSolid) {
    VolumeSource source;  // leopold's thin arms at h = 0.5 fold and cross as solved (docs/validity.md)
    source.shape = "leopold";
    source.h = 0.5;
    const PipelineResult distributed = run_distributed_pipeline(MPI_COMM_WORLD, source, PipelineOptions{});
    if (world_rank() != 0) return;
    ASSERT_TRUE(distributed.validity.has_value());
    EXPECT_FALSE(distributed.validity->before.valid());
    EXPECT_GT(distributed.validity->rounds, 0);
    EXPECT_TRUE(distributed.validity->after.valid());
    EXPECT_TRUE(check_mesh_validity(distributed.regularization.positions, distributed.surface.quads, distributed.field.normals).valid());
    EXPECT_EQ(distributed.stage_seconds.back().first, "validity");
}

TEST(Distributed, ErrorsReachEveryRankAlike) {
    VolumeSource missing;
    missing.input_path = "/nonexistent/volume.vol";
    try {
        run_distributed_pipeline(MPI_COMM_WORLD, missing, PipelineOptions{});
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent/volume.vol"), std::string::npos);
    }
    VolumeSource shape;
    shape.shape = "sphere9";
    PipelineOptions at;
    at.normals.kind = "at";
    EXPECT_THROW(run_distributed_pipeline(MPI_COMM_WORLD, shape, at), Error);
    PipelineOptions streaming;
    streaming.blocks.block_size = {8, 8, 8};
    EXPECT_THROW(run_distributed_pipeline(MPI_COMM_WORLD, shape, streaming), Error);
    // An error on one rank only.
    EXPECT_THROW(run_collectively(MPI_COMM_WORLD, [] {
                     if (world_rank() == world_size() - 1) throw Error("the last rank fails");
                 }),
                 Error);
}

}  // namespace
}  // namespace dsreg

int main(int argc, char** argv) {
    dsreg::DistributedSession session(&argc, &argv);
    testing::InitGoogleTest(&argc, argv);
    if (session.rank() != 0) {  // one report, from rank 0
        testing::TestEventListeners& listeners = testing::UnitTest::GetInstance()->listeners();
        delete listeners.Release(listeners.default_result_printer());
    }
    const int failed = RUN_ALL_TESTS() != 0;
    int any = failed;
    MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return any;
}
