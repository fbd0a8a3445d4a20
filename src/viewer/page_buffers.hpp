// dsreg — the binary arrays of an HTML page: little-endian Float32 / Uint32 / Int32 buffers,
// each written as base64 into <script type="application/octet-stream"> elements (internal to
// src/viewer).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "dsreg/mesh.hpp"

namespace dsreg::viewer {

/// One typed array: `count` values of `type` ("float32", "uint32" or "int32") as `bytes`.
struct PageBuffer {
    std::string type;
    std::int64_t count = 0;
    std::vector<unsigned char> bytes;
};

/// Rows of `points` minus `centre`, as Float32 x, y, z, x, y, z, ...
PageBuffer float32_points(const PointMatrix& points, const Eigen::Vector3d& centre);
/// Values as Float32 (NaN stays NaN).
PageBuffer float32_values(const Eigen::VectorXd& values);
/// Row-major integer matrix (face indices: "uint32", labels: "int32").
PageBuffer integer_matrix(const std::string& type, const std::int32_t* data, std::int64_t count);

/// The buffers of a page, each stored once: adding an array equal to one already there returns
/// the index of that one (layers sharing faces or a digital surface carry it once).
class PageBuffers {
public:
    /// Base64 text per <script> element: 16 MiB of text (12 MiB of data), far below the
    /// longest string a browser makes of an element's text.
    static constexpr std::size_t chunk_bytes = 12u << 20;

    int add(PageBuffer buffer);
    /// [{"type", "count", "chunks"}...], index i describing buffer i.
    nlohmann::json manifest() const;
    /// The elements <script type="application/octet-stream" id="dsreg-buffer-I-J">, J = chunk.
    void write_elements(std::ostream& out) const;

private:
    std::vector<PageBuffer> buffers_;
};

}  // namespace dsreg::viewer
