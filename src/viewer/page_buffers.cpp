#include "page_buffers.hpp"

#include <cstring>

#include "base64.hpp"

namespace dsreg::viewer {

namespace {

void append_little_endian(std::vector<unsigned char>& bytes, std::uint32_t word) {
    for (int shift = 0; shift < 32; shift += 8) bytes.push_back(static_cast<unsigned char>(word >> shift));
}

void append_float32(std::vector<unsigned char>& bytes, double value) {
    const float single = static_cast<float>(value);
    std::uint32_t word;
    std::memcpy(&word, &single, sizeof word);
    append_little_endian(bytes, word);
}

PageBuffer float32_buffer(std::int64_t count) {
    PageBuffer buffer{"float32", count, {}};
    buffer.bytes.reserve(std::size_t(count) * 4);
    return buffer;
}

}  // namespace

PageBuffer float32_points(const PointMatrix& points, const Eigen::Vector3d& centre) {
    PageBuffer buffer = float32_buffer(points.rows() * 3);
    for (Eigen::Index i = 0; i < points.rows(); ++i)
        for (int c = 0; c < 3; ++c) append_float32(buffer.bytes, points(i, c) - centre[c]);
    return buffer;
}

PageBuffer float32_values(const Eigen::VectorXd& values) {
    PageBuffer buffer = float32_buffer(values.size());
    for (Eigen::Index i = 0; i < values.size(); ++i) append_float32(buffer.bytes, values[i]);
    return buffer;
}

PageBuffer integer_matrix(const std::string& type, const std::int32_t* data, std::int64_t count) {
    PageBuffer buffer{type, count, {}};
    buffer.bytes.reserve(std::size_t(count) * 4);
    for (std::int64_t i = 0; i < count; ++i) append_little_endian(buffer.bytes, static_cast<std::uint32_t>(data[i]));
    return buffer;
}

int PageBuffers::add(PageBuffer buffer) {
    for (std::size_t i = 0; i < buffers_.size(); ++i)
        if (buffers_[i].type == buffer.type && buffers_[i].bytes == buffer.bytes) return int(i);
    buffers_.push_back(std::move(buffer));
    return int(buffers_.size() - 1);
}

nlohmann::json PageBuffers::manifest() const {
    nlohmann::json list = nlohmann::json::array();
    for (const PageBuffer& b : buffers_)
        list.push_back({{"type", b.type},
                        {"count", b.count},
                        {"chunks", b.bytes.empty() ? 1 : (b.bytes.size() + chunk_bytes - 1) / chunk_bytes}});
    return list;
}

void PageBuffers::write_elements(std::ostream& out) const {
    for (std::size_t i = 0; i < buffers_.size(); ++i) {
        const std::vector<unsigned char>& bytes = buffers_[i].bytes;
        std::size_t chunk = 0;
        for (std::size_t start = 0; start < bytes.size() || (start == 0 && chunk == 0); start += chunk_bytes, ++chunk) {
            const std::size_t size = std::min(chunk_bytes, bytes.size() - start);
            out << "<script type=\"application/octet-stream\" id=\"dsreg-buffer-" << i << '-' << chunk << "\">"
                << base64_encode(bytes.data() + start, size) << "</script>\n";
        }
    }
}

}  // namespace dsreg::viewer
