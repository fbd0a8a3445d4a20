// dsreg — local multipliers from a scalar volume (sampled at the vertices) or a text file.
#include "dsreg/local_weights.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"

namespace dsreg {

namespace {

std::string dims_text(const Index3& d) {
    return std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" + std::to_string(d[2]);
}

/// Mean of the in-grid voxels (a−1 … a) × (b−1 … b) × (c−1 … c) around pointel (a,b,c).
double mean_around_pointel(const ScalarVolume& volume, std::int64_t a, std::int64_t b, std::int64_t c) {
    double sum = 0;
    int count = 0;
    for (std::int64_t k = c - 1; k <= c; ++k)
        for (std::int64_t j = b - 1; j <= b; ++j)
            for (std::int64_t i = a - 1; i <= a; ++i)
                if (volume.grid.contains(i, j, k)) {
                    sum += volume.value(i, j, k);
                    ++count;
                }
    return count > 0 ? sum / count : 0.0;
}

/// Parses a whole token as a finite double (C syntax).
bool parse_number(const std::string& token, double& value) {
    errno = 0;
    char* end = nullptr;
    value = std::strtod(token.c_str(), &end);
    return end == token.c_str() + token.size() && errno != ERANGE && std::isfinite(value);
}

}  // namespace

Eigen::VectorXd sample_at_vertices(const ScalarVolume& volume, const DigitalSurface& surface) {
    if (volume.grid.dims != surface.grid.dims)
        throw Error("weight volume has dimensions " + dims_text(volume.grid.dims) + ", the surface's volume " +
                    dims_text(surface.grid.dims) + ": they must be the same grid");
    if (volume.values.size() != std::size_t(volume.grid.voxel_count()))
        throw Error("weight volume holds " + std::to_string(volume.values.size()) + " values for " +
                    std::to_string(volume.grid.voxel_count()) + " voxels");
    Eigen::VectorXd samples(surface.vertex_count());
    for (std::int64_t v = 0; v < surface.vertex_count(); ++v)
        samples[v] = mean_around_pointel(volume, surface.vertex_pointels(v, 0), surface.vertex_pointels(v, 1),
                                         surface.vertex_pointels(v, 2));
    return samples;
}

Eigen::VectorXd thin_part_alpha(const DigitalSurface& surface, const Eigen::VectorXd& face_reach, double reference,
                                const Eigen::VectorXd& face_sheetness, double sheet_reference) {
    if (!(reference > 0) || !std::isfinite(reference))
        throw Error("thin_part_alpha: the reference reach must be positive and finite");
    if (!(sheet_reference >= 0) || !std::isfinite(sheet_reference))
        throw Error("thin_part_alpha: the sheet reference reach must be zero or positive and finite");
    const std::int64_t m = surface.face_count();
    if (face_reach.size() != m || (face_sheetness.size() != 0 && face_sheetness.size() != m))
        throw Error("thin_part_alpha: one reach (and one sheetness, if any) per face expected (got " +
                    std::to_string(face_reach.size()) + " and " + std::to_string(face_sheetness.size()) + " for " +
                    std::to_string(m) + " faces)");
    Eigen::VectorXd alpha = Eigen::VectorXd::Ones(surface.vertex_count());
    for (std::int64_t f = 0; f < m; ++f) {
        const double sheetness = face_sheetness.size() > 0 ? std::clamp(face_sheetness[f], 0.0, 1.0) : 0.0;
        const double ratio = (reference - sheetness * (reference - sheet_reference)) / face_reach[f];
        for (int k = 0; k < 4; ++k) {
            double& a = alpha[surface.quads(f, k)];
            a = std::max(a, ratio * ratio);
        }
    }
    return alpha;
}

Eigen::VectorXd noise_fairness_gamma(const DigitalSurface& surface, const std::vector<std::int32_t>& faces_against_surfels,
                                     double gain, double full_share, int rings) {
    if (!(gain >= 0) || !std::isfinite(gain)) throw Error("noise fairness: the gain must be zero or positive");
    if (!(full_share > 0 && full_share <= 1)) throw Error("noise fairness: the full share must be in (0, 1]");
    if (rings < 0) throw Error("noise fairness: the number of rings must be zero or positive");
    const std::int64_t faces = surface.face_count();
    Eigen::VectorXd face_share = Eigen::VectorXd::Zero(faces);
    for (const std::int32_t f : faces_against_surfels) {
        if (f < 0 || f >= faces)
            throw Error("noise fairness: face " + std::to_string(f) + " of " + std::to_string(faces));
        face_share[f] = 1;
    }
    Eigen::VectorXd incident = Eigen::VectorXd::Zero(surface.vertex_count());
    for (std::int64_t f = 0; f < faces; ++f)
        for (int k = 0; k < 4; ++k) incident[surface.quads(f, k)] += 1;
    Eigen::VectorXd vertex_share(surface.vertex_count());
    for (int pass = 0;; ++pass) {
        vertex_share.setZero();
        for (std::int64_t f = 0; f < faces; ++f)
            for (int k = 0; k < 4; ++k) vertex_share[surface.quads(f, k)] += face_share[f];
        vertex_share = vertex_share.cwiseQuotient(incident.cwiseMax(1.0));
        if (pass == rings) break;
        face_share = face_means(surface.quads, vertex_share);
    }
    return vertex_share.unaryExpr([gain, full_share](double share) {
        const double strength = std::min(1.0, share / full_share);
        return 1 + gain * strength * strength;
    });
}

Eigen::VectorXd face_means(const FaceMatrix& faces, const Eigen::VectorXd& vertex_values) {
    Eigen::VectorXd means(faces.rows());
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
        double sum = 0;
        for (Eigen::Index c = 0; c < faces.cols(); ++c) {
            const std::int32_t v = faces(f, c);
            if (v < 0 || v >= vertex_values.size())
                throw Error("face_means: face " + std::to_string(f) + " refers to vertex " + std::to_string(v) + " of " +
                            std::to_string(vertex_values.size()));
            sum += vertex_values[v];
        }
        means[f] = sum / double(faces.cols());
    }
    return means;
}

Eigen::VectorXd read_values_file(const std::string& path, std::int64_t expected_count, const std::string& what) {
    errno = 0;
    std::ifstream in(path);
    if (!in) throw FileError(path + ": cannot open the " + what + " values file", errno);
    Eigen::VectorXd values(expected_count);
    std::int64_t count = 0;
    std::string line;
    for (std::int64_t line_number = 1; std::getline(in, line); ++line_number) {
        const std::size_t comment = line.find('#');
        if (comment != std::string::npos) line.erase(comment);
        std::istringstream tokens(line);
        std::string token;
        while (tokens >> token) {
            double value = 0;
            if (!parse_number(token, value))
                throw Error(path + ":" + std::to_string(line_number) + ": '" + token.substr(0, 40) + "' is not a finite number");
            if (count == expected_count)
                throw Error(path + ":" + std::to_string(line_number) + ": more than the " + std::to_string(expected_count) +
                            " " + what + " values expected");
            values[count++] = value;
        }
    }
    if (in.bad()) throw Error(path + ": read error");
    if (count != expected_count)
        throw Error(path + ": " + std::to_string(count) + " " + what + " values, " + std::to_string(expected_count) +
                    " expected (one per element, in mesh order)");
    return values;
}

void write_values_file(const std::string& path, const Eigen::VectorXd& values) {
    write_file_atomically(path, [&](std::ostream& out) {
        out.precision(17);
        for (Eigen::Index i = 0; i < values.size(); ++i) out << values[i] << '\n';
    });
}

}  // namespace dsreg
