// Sharp-feature lines of an Ambrosio–Tortorelli feature map, as OBJ polylines
// (see ambrosio_tortorelli.hpp).
#include <charconv>
#include <ostream>

#include "dsreg/ambrosio_tortorelli.hpp"
#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"

namespace dsreg {

namespace {

/// Feature edges in compressed adjacency form: the edges at vertex i are
/// edge_ids[offsets[i] .. offsets[i+1]), and edge k joins ends[k][0] and ends[k][1].
struct FeatureGraph {
    std::vector<std::array<std::int32_t, 2>> ends;
    std::vector<std::int64_t> offsets;
    std::vector<std::int32_t> edge_ids;

    std::int64_t degree(std::int32_t i) const { return offsets[std::size_t(i) + 1] - offsets[std::size_t(i)]; }
    std::int32_t other_end(std::int32_t edge, std::int32_t i) const {
        return ends[std::size_t(edge)][0] == i ? ends[std::size_t(edge)][1] : ends[std::size_t(edge)][0];
    }
};

/// Every mesh edge once (a closed manifold lists each edge as a→b in one face and b→a in the
/// other: keep a < b) whose two ends have v < threshold.
FeatureGraph feature_graph(const FaceMatrix& faces, std::int64_t vertex_count, const Eigen::VectorXd& v, double threshold) {
    FeatureGraph graph;
    const std::int64_t k = faces.cols();
    for (std::int64_t f = 0; f < faces.rows(); ++f)
        for (std::int64_t c = 0; c < k; ++c) {
            const std::int32_t a = faces(f, c), b = faces(f, (c + 1) % k);
            if (a < b && v[a] < threshold && v[b] < threshold) graph.ends.push_back({a, b});
        }
    graph.offsets.assign(std::size_t(vertex_count) + 1, 0);
    for (const auto& e : graph.ends) ++graph.offsets[std::size_t(e[0]) + 1], ++graph.offsets[std::size_t(e[1]) + 1];
    for (std::size_t i = 1; i < graph.offsets.size(); ++i) graph.offsets[i] += graph.offsets[i - 1];
    graph.edge_ids.resize(std::size_t(graph.offsets.back()));
    std::vector<std::int64_t> cursor(graph.offsets.begin(), graph.offsets.end() - 1);
    for (std::size_t e = 0; e < graph.ends.size(); ++e)
        for (std::int32_t end : graph.ends[e]) graph.edge_ids[std::size_t(cursor[std::size_t(end)]++)] = std::int32_t(e);
    return graph;
}

/// Follows unused edges from `start` along `first_edge` until a vertex where the chain cannot
/// continue uniquely (degree ≠ 2) or an edge already used (closing a loop).
std::vector<std::int32_t> walk_chain(const FeatureGraph& graph, std::vector<char>& used, std::int32_t start,
                                     std::int32_t first_edge) {
    std::vector<std::int32_t> chain{start};
    std::int32_t at = start, edge = first_edge;
    while (edge >= 0 && !used[std::size_t(edge)]) {
        used[std::size_t(edge)] = 1;
        at = graph.other_end(edge, at);
        chain.push_back(at);
        edge = -1;
        if (graph.degree(at) != 2) break;
        for (std::int64_t q = graph.offsets[std::size_t(at)]; q < graph.offsets[std::size_t(at) + 1]; ++q)
            if (!used[std::size_t(graph.edge_ids[std::size_t(q)])]) edge = graph.edge_ids[std::size_t(q)];
    }
    return chain;
}

void write_number(std::ostream& out, double x) {
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, x).ptr;  // shortest exact form
    out.write(text, end - text);
}

}  // namespace

std::vector<std::vector<std::int32_t>> feature_polylines(const FaceMatrix& quads, std::int64_t vertex_count,
                                                         const Eigen::VectorXd& v, double threshold) {
    if (v.size() != vertex_count) throw Error("feature lines: the feature map needs one value per vertex");
    const FeatureGraph graph = feature_graph(quads, vertex_count, v, threshold);
    std::vector<char> used(graph.ends.size(), 0);
    std::vector<std::vector<std::int32_t>> polylines;
    // Open chains start and end where other than two feature edges meet …
    for (std::int32_t i = 0; i < std::int32_t(vertex_count); ++i) {
        if (graph.degree(i) == 2 || graph.degree(i) == 0) continue;
        for (std::int64_t q = graph.offsets[std::size_t(i)]; q < graph.offsets[std::size_t(i) + 1]; ++q)
            if (!used[std::size_t(graph.edge_ids[std::size_t(q)])])
                polylines.push_back(walk_chain(graph, used, i, graph.edge_ids[std::size_t(q)]));
    }
    // … what is left are closed loops (every vertex of degree 2).
    for (std::size_t e = 0; e < graph.ends.size(); ++e)
        if (!used[e]) polylines.push_back(walk_chain(graph, used, graph.ends[e][0], std::int32_t(e)));
    return polylines;
}

void write_polylines_obj(const std::string& path, const PointMatrix& positions,
                         const std::vector<std::vector<std::int32_t>>& polylines) {
    std::vector<std::int64_t> obj_index(std::size_t(positions.rows()), 0);  // 1-based, 0 = unused
    std::vector<std::int32_t> used_vertices;
    for (const auto& line : polylines)
        for (std::int32_t i : line) {
            if (i < 0 || i >= positions.rows()) throw Error(path + ": polyline vertex " + std::to_string(i) + " out of range");
            if (obj_index[std::size_t(i)] == 0) {
                used_vertices.push_back(i);
                obj_index[std::size_t(i)] = std::int64_t(used_vertices.size());
            }
        }
    write_file_atomically(path, [&](std::ostream& out) {
        out << "# dsreg sharp-feature lines: " << polylines.size() << " polylines, " << used_vertices.size()
            << " vertices\n";
        for (std::int32_t i : used_vertices) {
            out << 'v';
            for (int d = 0; d < 3; ++d) out << ' ', write_number(out, positions(i, d));
            out << '\n';
        }
        for (const auto& line : polylines) {
            out << 'l';
            for (std::int32_t i : line) out << ' ' << obj_index[std::size_t(i)];
            out << '\n';
        }
    });
}

}  // namespace dsreg
