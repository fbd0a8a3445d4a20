// dsreg_bench_mesh_validity MESH... — checks mesh files as written (any format read_mesh reads) by
// the definition of mesh_validity.hpp: CGAL self-intersections and degenerate triangles of the
// triangles users get (quads split along the shorter diagonal), and folds against the file's face
// normals when it carries them. One JSON object per file on standard output. bench/validity.sh uses
// it to check what dsreg wrote, after the rounding of the file format (STL: 32-bit floats).
#include <cstdio>
#include <exception>
#include <string>

#include "dsreg/mesh_io.hpp"
#include "dsreg/mesh_validity.hpp"

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s MESH...\n", argv[0]);
        return 1;
    }
    try {
        for (int i = 1; i < argc; ++i) {
            const dsreg::PolygonMesh mesh = dsreg::read_mesh(argv[i]);
            const dsreg::MeshValidity validity = dsreg::check_mesh_validity(mesh.vertices, mesh.faces, mesh.face_normals);
            std::printf("{\"file\": \"%s\", \"faces\": %lld, \"intersecting_pairs\": %lld, \"degenerate_triangles\": %lld, "
                        "\"folded_faces\": %lld, \"field\": %s, \"valid\": %s}\n",
                        argv[i], static_cast<long long>(mesh.faces.rows()),
                        static_cast<long long>(validity.intersecting_pairs),
                        static_cast<long long>(validity.degenerate_triangles),
                        static_cast<long long>(validity.folded_faces), mesh.face_normals.rows() ? "true" : "false",
                        validity.valid() ? "true" : "false");
        }
    } catch (const std::exception& error) {
        std::fprintf(stderr, "%s\n", error.what());
        return 1;
    }
    return 0;
}
