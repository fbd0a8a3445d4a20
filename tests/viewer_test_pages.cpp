// Writes the HTML pages of the browser test (viewer_browser_test.py) that only the library can
// make: meshes with per-face label pairs, which no mesh file dsreg reads carries yet.
//   viewer_test_pages FOLDER   writes FOLDER/labels.html and FOLDER/labels-open.html
//
// Both show a sphere made of quads (a cube's faces, n×n each, pushed onto the unit sphere). Every
// face gets the label pair (quadrant, outside): quadrant = 1 + [x > 0] + 2 [z > 0] at its centre,
// so that seen from −y (azimuth 0, elevation 0) the four quadrant labels are all in view.
//  * labels.html: the closed sphere, outside label 0: the front of the faces is seen, so the
//    colours of labels 1, 2, 3, 4.
//  * labels-open.html: only the half y > 0, outside label 5: from −y one looks into the bowl at
//    the back of its faces, so the colour of label 5 (and none of labels 1-4 but on the rim).
#include <array>
#include <iostream>
#include <map>
#include <vector>

#include "dsreg/error.hpp"
#include "dsreg/html_view.hpp"

namespace {

using dsreg::FaceLabelMatrix;
using dsreg::PolygonMesh;

struct LabelledMesh {
    PolygonMesh mesh;
    FaceLabelMatrix labels;
};

/// The sphere described above, keeping the faces whose centre has y > min_y.
LabelledMesh labelled_sphere(int n, double min_y, int outside_label) {
    std::map<std::array<int, 3>, int> index;  // lattice point of [-n, n]³ (step 2) -> vertex
    std::vector<Eigen::Vector3d> vertices;
    std::vector<std::array<int, 4>> faces;
    std::vector<std::array<int, 2>> labels;
    const auto vertex = [&](const std::array<int, 3>& p) {
        const auto [it, added] = index.emplace(p, int(vertices.size()));
        if (added) vertices.push_back(Eigen::Vector3d(p[0], p[1], p[2]).normalized());
        return it->second;
    };
    for (int axis = 0; axis < 3; ++axis)
        for (int side : {-1, 1})
            for (int x = 0; x < n; ++x)
                for (int y = 0; y < n; ++y) {
                    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
                    std::array<int, 4> face;
                    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
                    const int corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
                    for (int c = 0; c < 4; ++c) {
                        std::array<int, 3> p;
                        p[axis] = side * n;
                        p[a] = -n + 2 * (x + corners[c][0]);
                        p[b] = -n + 2 * (y + corners[c][1]);
                        face[side > 0 ? c : 3 - c] = vertex(p);  // counter-clockwise seen from outside
                        centre += Eigen::Vector3d(p[0], p[1], p[2]);
                    }
                    if (centre.y() / (4.0 * n) <= min_y) continue;
                    faces.push_back(face);
                    labels.push_back({1 + (centre.x() > 0) + 2 * (centre.z() > 0), outside_label});
                }
    LabelledMesh result;
    result.mesh.vertices.resize(Eigen::Index(vertices.size()), 3);
    for (std::size_t i = 0; i < vertices.size(); ++i) result.mesh.vertices.row(Eigen::Index(i)) = vertices[i].transpose();
    result.mesh.faces.resize(Eigen::Index(faces.size()), 4);
    result.labels.resize(Eigen::Index(faces.size()), 2);
    for (std::size_t f = 0; f < faces.size(); ++f) {
        for (int c = 0; c < 4; ++c) result.mesh.faces(Eigen::Index(f), c) = faces[f][std::size_t(c)];
        result.labels.row(Eigen::Index(f)) << labels[f][0], labels[f][1];
    }
    return result;
}

void write_page(const std::string& path, const std::string& title, const LabelledMesh& sphere) {
    dsreg::ViewPage page;
    page.title = title;
    page.layers.push_back(dsreg::ViewLayer{title, sphere.mesh, std::nullopt, sphere.labels, {{"labels", "synthetic"}}});
    dsreg::write_html_view(path, page);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::cerr << "usage: viewer_test_pages FOLDER\n";
        return 2;
    }
    try {
        const std::string folder = argv[1];
        write_page(folder + "/labels.html", "labelled sphere", labelled_sphere(16, -2.0, 0));
        write_page(folder + "/labels-open.html", "labelled bowl", labelled_sphere(16, 0.0, 5));
    } catch (const dsreg::Error& e) {
        std::cerr << "viewer_test_pages: " << e.what() << '\n';
        return 1;
    }
    return 0;
}
