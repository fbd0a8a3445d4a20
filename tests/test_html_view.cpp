// Tests of the HTML viewer's page (include/dsreg/html_view.hpp) without a browser: the data the
// page carries (decoded from its base64 buffers here, with a decoder of the test's own) equals
// the meshes and the fields computed from them; names cannot break out of their element; the
// page refers to nothing outside itself; bad layers are refused and no file is left.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "dsreg/ambrosio_tortorelli.hpp"
#include "dsreg/error.hpp"
#include "dsreg/html_view.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

namespace fs = std::filesystem;
using test::error_message;

/// Cube [0,2]³ moved by `offset`, 6 outward quads; vertex (x,y,z) has index x + 2y + 4z; u is the
/// outward axis normal of each face.
PolygonMesh make_cube(const Eigen::RowVector3d& offset = Eigen::RowVector3d::Zero()) {
    PolygonMesh cube;
    cube.vertices.resize(8, 3);
    for (int i = 0; i < 8; ++i) cube.vertices.row(i) = 2.0 * Eigen::RowVector3d(i & 1, (i >> 1) & 1, (i >> 2) & 1) + offset;
    cube.faces.resize(6, 4);
    cube.faces << 0, 2, 3, 1, 4, 5, 7, 6, 0, 1, 5, 4, 2, 6, 7, 3, 0, 4, 6, 2, 1, 3, 7, 5;
    cube.face_normals.resize(6, 3);
    cube.face_normals << 0, 0, -1, 0, 0, 1, 0, -1, 0, 0, 1, 0, -1, 0, 0, 1, 0, 0;
    return cube;
}

ViewPage one_layer_page(const PolygonMesh& mesh) {
    ViewPage page;
    page.title = "test";
    page.layers.push_back(ViewLayer{"cube", mesh, std::nullopt, {}, {}});
    return page;
}

std::string page_text(const ViewPage& page) {
    std::ostringstream out;
    dsreg::write_html_view(out, page);
    return out.str();
}

/// The text of the element whose start tag contains `id="ID"`.
std::string element_text(const std::string& html, const std::string& id) {
    const std::size_t tag = html.find("id=\"" + id + "\"");
    if (tag == std::string::npos) return {};
    const std::size_t start = html.find('>', tag) + 1;
    return html.substr(start, html.find("</script>", start) - start);
}

std::vector<unsigned char> decode_base64(const std::string& text) {
    const std::string digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::vector<unsigned char> bytes;
    unsigned bits = 0;
    int bit_count = 0;
    for (char c : text) {
        if (c == '=') break;
        const std::size_t value = digits.find(c);
        EXPECT_NE(value, std::string::npos) << "not base64: " << c;
        bits = (bits << 6) | unsigned(value);
        bit_count += 6;
        if (bit_count >= 8) {
            bit_count -= 8;
            bytes.push_back(static_cast<unsigned char>(bits >> bit_count));
        }
    }
    return bytes;
}

/// A decoded page: its JSON data and buffer i as little-endian 32-bit words.
struct Page {
    nlohmann::json data;
    std::string html;

    explicit Page(const ViewPage& page) : html(page_text(page)) { data = nlohmann::json::parse(element_text(html, "dsreg-page")); }

    std::vector<unsigned char> bytes(int index) const {
        std::vector<unsigned char> all;
        for (int chunk = 0; chunk < data["buffers"][index]["chunks"].get<int>(); ++chunk) {
            const auto part = decode_base64(element_text(html, "dsreg-buffer-" + std::to_string(index) + "-" + std::to_string(chunk)));
            all.insert(all.end(), part.begin(), part.end());
        }
        EXPECT_EQ(all.size(), 4 * data["buffers"][index]["count"].get<std::size_t>());
        return all;
    }
    std::vector<float> floats(const nlohmann::json& index) const {
        EXPECT_EQ(data["buffers"][index.get<int>()]["type"], "float32");
        const auto b = bytes(index.get<int>());
        std::vector<float> values(b.size() / 4);
        for (std::size_t i = 0; i < values.size(); ++i) {
            const std::uint32_t word = std::uint32_t(b[4 * i]) | std::uint32_t(b[4 * i + 1]) << 8 |
                                       std::uint32_t(b[4 * i + 2]) << 16 | std::uint32_t(b[4 * i + 3]) << 24;
            std::memcpy(&values[i], &word, 4);
        }
        return values;
    }
    std::vector<std::int64_t> integers(const nlohmann::json& index) const {
        const std::string type = data["buffers"][index.get<int>()]["type"];
        const auto b = bytes(index.get<int>());
        std::vector<std::int64_t> values(b.size() / 4);
        for (std::size_t i = 0; i < values.size(); ++i) {
            const std::uint32_t word = std::uint32_t(b[4 * i]) | std::uint32_t(b[4 * i + 1]) << 8 |
                                       std::uint32_t(b[4 * i + 2]) << 16 | std::uint32_t(b[4 * i + 3]) << 24;
            values[i] = type == "int32" ? std::int64_t(std::int32_t(word)) : std::int64_t(word);
        }
        return values;
    }
};

// ---- the fields the page colours by ----------------------------------------------------------

TEST(FaceDeviation, IsTheAngleBetweenTheFaceNormalAndU) {
    PolygonMesh cube = make_cube();
    const double angle = 0.3;  // u of face 1 (z = 1, normal +z) turned by 0.3 rad about x
    cube.face_normals.row(1) << 0, -std::sin(angle), std::cos(angle);
    cube.face_normals.row(4) << 1, 0, 0;  // face 4 (x = 0, normal -x): u points inward, 180 degrees
    const Eigen::VectorXd degrees = dsreg::face_deviation_degrees(cube.vertices, cube.faces, cube.face_normals);
    ASSERT_EQ(degrees.size(), 6);
    for (int f : {0, 2, 3, 5}) EXPECT_NEAR(degrees[f], 0.0, 1e-12);
    EXPECT_NEAR(degrees[1], angle * 180 / M_PI, 1e-12);
    EXPECT_NEAR(degrees[4], 180.0, 1e-12);
}

TEST(FaceDeviation, IsUndefinedForAFaceWithoutArea) {
    PolygonMesh cube = make_cube();
    cube.vertices.row(7) = cube.vertices.row(6);  // face 1 (4,5,7,6) becomes the segment 4-6: no area
    cube.vertices.row(5) = cube.vertices.row(4);  // (faces 0, 2, 3 keep theirs)
    const Eigen::VectorXd degrees = dsreg::face_deviation_degrees(cube.vertices, cube.faces, cube.face_normals);
    EXPECT_TRUE(std::isnan(degrees[1]));
    EXPECT_NEAR(degrees[0], 0.0, 1e-12);
    EXPECT_CONTAINS(error_message([&] { dsreg::face_deviation_degrees(cube.vertices, cube.faces, PointMatrix(2, 3)); }),
                    "2 field vectors for 6 faces");
}

TEST(VertexDisplacements, AreTheDistancesBetweenCorrespondingVertices) {
    const PolygonMesh cube = make_cube();
    PointMatrix moved = cube.vertices;
    moved.row(3) += Eigen::RowVector3d(3, 4, 0);
    const Eigen::VectorXd d = dsreg::vertex_displacements(moved, cube.vertices);
    EXPECT_DOUBLE_EQ(d[3], 5.0);
    EXPECT_DOUBLE_EQ(d.sum(), 5.0);
}

// ---- what the page carries -------------------------------------------------------------------

TEST(HtmlView, BuffersHoldThePositionsAboutTheCentreAndTheFaces) {
    const PolygonMesh cube = make_cube(Eigen::RowVector3d(1e6, -2.5, 0.125));  // far from the origin
    const Page page(one_layer_page(cube));
    const auto centre = page.data["centre"].get<std::vector<double>>();
    EXPECT_DOUBLE_EQ(centre[0], 1e6 + 1);
    EXPECT_DOUBLE_EQ(centre[1], -1.5);
    EXPECT_DOUBLE_EQ(centre[2], 1.125);
    const nlohmann::json& surface = page.data["layers"][0]["surface"];
    EXPECT_EQ(surface["vertex_count"], 8);
    EXPECT_EQ(surface["face_count"], 6);
    EXPECT_EQ(surface["face_size"], 4);
    const std::vector<float> positions = page.floats(surface["positions"]);
    ASSERT_EQ(positions.size(), 24u);
    for (int i = 0; i < 8; ++i)
        for (int c = 0; c < 3; ++c)  // relative to the centre: exact in Float32 here (±1)
            EXPECT_EQ(double(positions[3 * i + c]), cube.vertices(i, c) - centre[c]) << i << ',' << c;
    const std::vector<std::int64_t> faces = page.integers(surface["faces"]);
    ASSERT_EQ(faces.size(), 24u);
    for (int f = 0; f < 6; ++f)
        for (int k = 0; k < 4; ++k) EXPECT_EQ(faces[4 * f + k], cube.faces(f, k));
}

TEST(HtmlView, CarriesTheDeviationPerFaceWithItsRange) {
    PolygonMesh cube = make_cube();
    cube.face_normals.row(2) << 0, -std::cos(0.1), std::sin(0.1);
    const Page page(one_layer_page(cube));
    const nlohmann::json& deviation = page.data["layers"][0]["surface"]["deviation"];
    EXPECT_EQ(deviation["unit"], "degrees");
    const std::vector<float> values = page.floats(deviation["buffer"]);
    const Eigen::VectorXd expected = dsreg::face_deviation_degrees(cube.vertices, cube.faces, cube.face_normals);
    ASSERT_EQ(values.size(), 6u);
    for (int f = 0; f < 6; ++f) EXPECT_FLOAT_EQ(values[f], float(expected[f]));
    EXPECT_NEAR(values[2], 0.1 * 180 / M_PI, 1e-4);
    // The colour range ends at the 99th percentile: here the largest of the six values.
    EXPECT_DOUBLE_EQ(deviation["range"][0], 0.0);
    EXPECT_NEAR(deviation["range"][1].get<double>(), expected[2], 1e-12);
}

TEST(HtmlView, WithoutUThereIsNoDeviation) {
    PolygonMesh cube = make_cube();
    cube.face_normals.resize(0, 3);
    const Page page(one_layer_page(cube));
    EXPECT_FALSE(page.data["layers"][0]["surface"].contains("deviation"));
}

TEST(HtmlView, DigitalSurfaceGivesTheDisplacementAndSharesEqualBuffers) {
    const PolygonMesh digital = make_cube();
    PolygonMesh mesh = digital;
    mesh.vertices.row(6) += Eigen::RowVector3d(0, 0, 0.25);
    ViewPage view = one_layer_page(mesh);
    view.layers[0].digital = digital;
    const Page page(view);
    const nlohmann::json& layer = page.data["layers"][0];
    ASSERT_TRUE(layer.contains("digital"));
    EXPECT_EQ(layer["digital"]["faces"], layer["surface"]["faces"]) << "the same faces are sent once";
    EXPECT_NE(layer["digital"]["positions"], layer["surface"]["positions"]);
    ASSERT_EQ(layer["vertex_fields"].size(), 1u);
    const nlohmann::json& field = layer["vertex_fields"][0];
    EXPECT_EQ(field["kind"], "length");
    const std::vector<float> displacement = page.floats(field["buffer"]);
    for (int i = 0; i < 8; ++i) EXPECT_FLOAT_EQ(displacement[i], i == 6 ? 0.25f : 0.0f);
    EXPECT_DOUBLE_EQ(field["range"][1], 0.25);
    // The digital surface's own faces are compared with the same u.
    const std::vector<float> digital_deviation = page.floats(layer["digital"]["deviation"]["buffer"]);
    for (float d : digital_deviation) EXPECT_FLOAT_EQ(d, 0.0f);
}

TEST(HtmlView, FeatureMapGivesItsFeatureEdges) {
    PolygonMesh cube = make_cube();
    Eigen::VectorXd v = Eigen::VectorXd::Ones(8);
    v[0] = v[1] = v[3] = 0.1;  // edges 0-1 and 1-3 have both ends below 0.5; 0-3 is no edge
    cube.vertex_scalars = {{"v", v}, {"curvature", Eigen::VectorXd::LinSpaced(8, -1, 6)}};
    const Page page(one_layer_page(cube));
    const nlohmann::json& layer = page.data["layers"][0];
    ASSERT_EQ(layer["vertex_fields"].size(), 2u);
    EXPECT_EQ(layer["vertex_fields"][0]["kind"], "feature_map");
    EXPECT_EQ(layer["vertex_fields"][1]["kind"], "scalar");
    EXPECT_EQ(layer["vertex_fields"][1]["name"], "curvature");
    EXPECT_DOUBLE_EQ(layer["vertex_fields"][1]["range"][0], -1.0);
    EXPECT_DOUBLE_EQ(layer["vertex_fields"][1]["range"][1], 6.0);
    std::vector<std::int64_t> edges = page.integers(layer["feature_edges"]);
    ASSERT_EQ(edges.size(), 4u);
    std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
    for (std::size_t i = 0; i < edges.size(); i += 2) pairs.emplace_back(std::min(edges[i], edges[i + 1]), std::max(edges[i], edges[i + 1]));
    std::sort(pairs.begin(), pairs.end());
    EXPECT_EQ(pairs, (std::vector<std::pair<std::int64_t, std::int64_t>>{{0, 1}, {1, 3}}));
}

TEST(HtmlView, CarriesTheLabelPairsAndTheirValues) {
    ViewPage view = one_layer_page(make_cube());
    view.layers[0].face_labels.resize(6, 2);
    view.layers[0].face_labels << 3, 0, 3, 0, 7, 3, 7, -2, 3, 0, 3, 0;
    const Page page(view);
    const nlohmann::json& labels = page.data["layers"][0]["surface"]["labels"];
    EXPECT_EQ(labels["values"], (std::vector<int>{-2, 0, 3, 7}));
    const std::vector<std::int64_t> pairs = page.integers(labels["buffer"]);
    ASSERT_EQ(pairs.size(), 12u);
    for (int f = 0; f < 6; ++f)
        for (int side = 0; side < 2; ++side) EXPECT_EQ(pairs[2 * f + side], view.layers[0].face_labels(f, side));
}

TEST(HtmlView, NamesCannotEndTheirElement) {
    ViewPage view = one_layer_page(make_cube());
    view.title = "</script><script>alert(1)</script> <!-- é 立方体";
    view.layers[0].name = "</SCRIPT>x";
    view.summary = {{"input", "a</script>b"}};
    const Page page(view);  // the JSON element parses whole
    EXPECT_EQ(page.data["title"], view.title);
    EXPECT_EQ(page.data["layers"][0]["name"], view.layers[0].name);
    EXPECT_EQ(page.data["summary"][0][1], "a</script>b");
    EXPECT_EQ(element_text(page.html, "dsreg-page").find('<'), std::string::npos);
}

TEST(HtmlView, InvalidUtf8InNamesIsReplaced) {
    ViewPage view = one_layer_page(make_cube());
    view.layers[0].name = "mesh\xff\xfe.ply";
    const Page page(view);
    EXPECT_EQ(page.data["layers"][0]["name"], "mesh\xEF\xBF\xBD\xEF\xBF\xBD.ply");  // U+FFFD twice
}

TEST(HtmlView, NothingOutsideTheInlinedLibraryNamesAUrl) {
    const std::string html = page_text(one_layer_page(make_cube()));
    // Take out the two elements of three.js (its licence and comments name web sites).
    std::string rest = html;
    for (const std::string id : {"dsreg-three", "dsreg-orbit-controls"}) {
        const std::size_t start = rest.find("<script id=\"" + id + "\">");
        ASSERT_NE(start, std::string::npos) << id;
        const std::size_t end = rest.find("</script>", start);
        rest.erase(start, end - start);
    }
    EXPECT_EQ(rest.find("://"), std::string::npos) << rest.substr(rest.find("://") - 40, 80);
    EXPECT_NE(html.find("Content-Security-Policy\" content=\"default-src 'none';"), std::string::npos);
    EXPECT_EQ(html.find("<link"), std::string::npos);
    EXPECT_EQ(html.find(" src="), std::string::npos);
    // three.js and its licence are inside.
    EXPECT_NE(html.find("REVISION=\"111\""), std::string::npos);
    EXPECT_NE(html.find("Permission is hereby granted"), std::string::npos);
    EXPECT_NE(html.find("THREE.OrbitControls"), std::string::npos);
}

// ---- refused pages ---------------------------------------------------------------------------

TEST(HtmlView, RefusesAMeshWithoutFaces) {
    PolygonMesh points;
    points.vertices = PointMatrix::Random(5, 3);
    points.faces.resize(0, 3);
    const std::string message = error_message([&] { page_text(one_layer_page(points)); });
    EXPECT_CONTAINS(message, "layer 1 'cube'");
    EXPECT_CONTAINS(message, "no faces (5 vertices)");
}

TEST(HtmlView, RefusesInconsistentLayers) {
    PolygonMesh cube = make_cube();
    cube.faces(2, 1) = 8;
    EXPECT_CONTAINS(error_message([&] { page_text(one_layer_page(cube)); }), "refers to vertex 8");
    cube = make_cube();
    cube.vertices(3, 1) = std::nan("");
    EXPECT_CONTAINS(error_message([&] { page_text(one_layer_page(cube)); }), "non-finite");

    ViewPage view = one_layer_page(make_cube());
    PolygonMesh digital = make_cube();
    digital.vertices.conservativeResize(7, 3);
    digital.faces.resize(1, 3);
    digital.faces << 0, 1, 2;
    digital.face_normals.resize(0, 3);
    view.layers[0].digital = digital;
    EXPECT_CONTAINS(error_message([&] { page_text(view); }), "the digital surface has 7 vertices, the mesh 8");

    view = one_layer_page(make_cube());
    view.layers[0].face_labels.resize(5, 2);
    EXPECT_CONTAINS(error_message([&] { page_text(view); }), "5 label pairs for 6 faces");

    view = one_layer_page(make_cube());
    view.layers[0].mesh.vertex_scalars = {{"v", Eigen::VectorXd::Ones(3)}};
    EXPECT_CONTAINS(error_message([&] { page_text(view); }), "vertex scalar 'v' has 3 values for 8 vertices");

    EXPECT_CONTAINS(error_message([&] { page_text(ViewPage{}); }), "no mesh to show");
}

TEST(HtmlView, RefusesMoreFacesThanTheLimit) {
    ViewPage view = one_layer_page(make_cube());
    view.layers[0].digital = make_cube();
    view.max_faces = 11;  // 6 + 6 faces
    EXPECT_CONTAINS(error_message([&] { page_text(view); }), "12 faces in all, more than a page can show (at most 11");
    view.max_faces = 12;
    EXPECT_NO_THROW(page_text(view));
}

TEST(HtmlView, FailedWriteLeavesNoFileAndKeepsAnExistingOne) {
    const fs::path folder = fs::temp_directory_path() / ("dsreg_html_view_" + std::to_string(::getpid()));
    fs::create_directories(folder);
    const std::string path = (folder / "page.html").string();
    {
        std::ofstream(path) << "old";
    }
    PolygonMesh empty;
    empty.faces.resize(0, 3);
    EXPECT_CONTAINS(error_message([&] { dsreg::write_html_view(path, one_layer_page(empty)); }), path + ": layer 1");
    std::ifstream in(path);
    std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(content, "old");
    EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator()), 1) << "no temporary file left";

    const std::string missing = (folder / "no" / "page.html").string();
    EXPECT_CONTAINS(error_message([&] { dsreg::write_html_view(missing, one_layer_page(make_cube())); }), missing);
    dsreg::write_html_view(path, one_layer_page(make_cube()));
    EXPECT_GT(fs::file_size(path), 800000u);  // three.js is inside
    fs::remove_all(folder);
}

}  // namespace
}  // namespace dsreg
