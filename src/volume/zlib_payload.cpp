// dsreg — zlib payloads of .vol / .longvol version 3: bounded streaming inflate into a
// SampleWriter, and streaming deflate for the writers.
#include <algorithm>
#include <limits>

#include "volume_io_internal.hpp"

namespace dsreg::volume_io_detail {

namespace {

/// Deflate cannot compress better than about 1032:1 (a 258-byte match costs at least two bits);
/// the slack covers the zlib header, the final block and the checksum.
constexpr std::uint64_t kMaxInflateRatio = 1032;
constexpr std::uint64_t kInflateSlack = 1024;

std::string zlib_problem(const z_stream& stream, int code) {
    if (stream.msg != nullptr) return stream.msg;
    return "zlib error code " + std::to_string(code);
}

/// Owns an inflate stream for the duration of one decode.
class Inflater {
public:
    explicit Inflater(const InputFile& file) {
        const int code = inflateInit(&stream_);
        if (code != Z_OK) file.fail("cannot initialise zlib: " + zlib_problem(stream_, code));
    }
    ~Inflater() { inflateEnd(&stream_); }
    Inflater(const Inflater&) = delete;
    Inflater& operator=(const Inflater&) = delete;
    z_stream& stream() { return stream_; }

private:
    z_stream stream_{};
};

/// Throws for inflate() results that mean the stream is unusable.
void check_inflate_result(const InputFile& file, const z_stream& stream, int code) {
    if (code == Z_OK || code == Z_STREAM_END || code == Z_BUF_ERROR) return;
    if (code == Z_NEED_DICT) file.fail("corrupt zlib payload: the stream needs a preset dictionary");
    if (code == Z_MEM_ERROR) file.fail("not enough memory to inflate the zlib payload");
    file.fail("corrupt zlib payload: " + zlib_problem(stream, code));
}

}  // namespace

void require_plausible_zlib_payload(const InputFile& file, std::uint64_t expected_bytes, const std::string& description) {
    const std::uint64_t compressed = file.remaining();
    const std::uint64_t max_bytes =
        compressed > (std::numeric_limits<std::uint64_t>::max() - kInflateSlack) / kMaxInflateRatio
            ? std::numeric_limits<std::uint64_t>::max()
            : compressed * kMaxInflateRatio + kInflateSlack;
    if (expected_bytes > max_bytes)
        file.fail("truncated or lying header: " + description + ", but the " + std::to_string(compressed) +
                  "-byte zlib payload can inflate to at most " + std::to_string(max_bytes) + " bytes");
}

void decode_zlib_payload(InputFile& file, std::uint64_t expected_bytes, SampleWriter& sink, const std::string& description) {
    Inflater inflater(file);
    z_stream& stream = inflater.stream();
    std::vector<std::uint8_t> input(std::size_t(1) << 16);
    std::vector<std::uint8_t> output(std::size_t(1) << 18);
    std::uint64_t produced = 0;
    bool stream_ended = false;

    while (!stream_ended) {
        if (stream.avail_in == 0) {
            const std::size_t got = file.read(input.data(), input.size());
            if (got == 0)
                file.fail("truncated payload: " + description + ", but the zlib stream is cut off after inflating " +
                          std::to_string(produced) + " bytes");
            stream.next_in = input.data();
            stream.avail_in = static_cast<uInt>(got);
        }
        const std::uint64_t room = expected_bytes - produced;
        if (room == 0) {
            // Every expected byte is there: the stream may only end now. Probe for one more byte.
            std::uint8_t probe = 0;
            stream.next_out = &probe;
            stream.avail_out = 1;
            const int code = inflate(&stream, Z_NO_FLUSH);
            check_inflate_result(file, stream, code);
            if (stream.avail_out == 0)
                file.fail("payload larger than header says: " + description + ", but the zlib stream inflates to more than " +
                          std::to_string(expected_bytes) + " bytes");
            if (code == Z_BUF_ERROR && stream.avail_in > 0) file.fail("corrupt zlib payload: inflate makes no progress");
            stream_ended = code == Z_STREAM_END;
            continue;
        }
        const auto window = static_cast<uInt>(std::min<std::uint64_t>(output.size(), room));
        stream.next_out = output.data();
        stream.avail_out = window;
        const int code = inflate(&stream, Z_NO_FLUSH);
        check_inflate_result(file, stream, code);
        const std::size_t got = window - stream.avail_out;
        sink.consume(output.data(), got);
        produced += got;
        if (code == Z_BUF_ERROR && stream.avail_in > 0) file.fail("corrupt zlib payload: inflate makes no progress");
        stream_ended = code == Z_STREAM_END;
    }

    if (produced < expected_bytes)
        file.fail("truncated payload: " + description + ", but the zlib stream inflates to only " + std::to_string(produced) +
                  " bytes");
    const std::uint64_t trailing = stream.avail_in + file.remaining();
    if (trailing > 0) file.fail(std::to_string(trailing) + " trailing bytes after the end of the zlib stream");
}

// ----------------------------------------------------------------------------------------------
// PayloadWriter

PayloadWriter::PayloadWriter(const std::string& path, std::ostream& out, bool compress)
    : path_(path), out_(out), compress_(compress) {
    if (!compress_) return;
    const int code = deflateInit(&stream_, Z_DEFAULT_COMPRESSION);
    if (code != Z_OK) fail(path_, "cannot initialise zlib: " + zlib_problem(stream_, code));
    chunk_.resize(std::size_t(1) << 16);
}

PayloadWriter::~PayloadWriter() {
    if (compress_) deflateEnd(&stream_);
}

void PayloadWriter::deflate_pending(int flush) {
    // Without Z_FINISH, a full output chunk means deflate may have more to say; with Z_FINISH,
    // go on until the stream is closed.
    bool more = true;
    while (more) {
        stream_.next_out = chunk_.data();
        stream_.avail_out = static_cast<uInt>(chunk_.size());
        const int code = deflate(&stream_, flush);
        if (code == Z_STREAM_ERROR) fail(path_, "zlib compression failed: " + zlib_problem(stream_, code));
        out_.write(reinterpret_cast<const char*>(chunk_.data()),
                   static_cast<std::streamsize>(chunk_.size() - stream_.avail_out));
        more = flush == Z_FINISH ? code != Z_STREAM_END : stream_.avail_out == 0;
    }
}

void PayloadWriter::write(const std::uint8_t* data, std::size_t count) {
    if (!compress_) {
        out_.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(count));
        return;
    }
    constexpr std::size_t max_piece = std::size_t(1) << 30;  // avail_in is 32-bit
    while (count > 0) {
        const std::size_t piece = std::min(count, max_piece);
        stream_.next_in = const_cast<Bytef*>(data);
        stream_.avail_in = static_cast<uInt>(piece);
        deflate_pending(Z_NO_FLUSH);
        data += piece;
        count -= piece;
    }
}

void PayloadWriter::finish() {
    if (finished_) return;
    finished_ = true;
    if (compress_) {
        stream_.next_in = nullptr;
        stream_.avail_in = 0;
        deflate_pending(Z_FINISH);
    }
}

}  // namespace dsreg::volume_io_detail
