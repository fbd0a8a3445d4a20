// dsreg — compressed payloads: bounded streaming inflate of zlib and gzip streams (.vol v3,
// .nii.gz, NRRD gzip, MetaImage CompressedData) into a SampleWriter, and streaming deflate for
// the writers.
#include <algorithm>
#include <cstring>
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

/// Throws for inflate() results that mean the stream is unusable.
void check_inflate_result(const InputFile& file, const char* name, const z_stream& stream, int code) {
    if (code == Z_OK || code == Z_STREAM_END || code == Z_BUF_ERROR) return;
    const std::string kind = name;
    if (code == Z_NEED_DICT) file.fail("corrupt " + kind + " payload: the stream needs a preset dictionary");
    if (code == Z_MEM_ERROR) file.fail("not enough memory to inflate the " + kind + " payload");
    file.fail("corrupt " + kind + " payload: " + zlib_problem(stream, code));
}

int window_bits(CompressedContainer container) {
    switch (container) {
    case CompressedContainer::Zlib: return 15;
    case CompressedContainer::Gzip: return 15 + 16;
    case CompressedContainer::ZlibOrGzip: return 15 + 32;
    }
    return 15;
}

}  // namespace

// ----------------------------------------------------------------------------------------------
// InflateStream

InflateStream::InflateStream(InputFile& file, CompressedContainer container)
    : file_(file), container_(container), input_(std::size_t(1) << 16) {
    const int code = inflateInit2(&stream_, window_bits(container));
    if (code != Z_OK) file.fail("cannot initialise zlib: " + zlib_problem(stream_, code));
}

InflateStream::~InflateStream() { inflateEnd(&stream_); }

const char* InflateStream::name() const { return container_ == CompressedContainer::Gzip ? "gzip" : "zlib"; }

bool InflateStream::next_member_follows() {
    // gzip allows several members one after the other (pigz --independent, bgzip): go on if the
    // input continues with the gzip magic bytes.
    if (container_ == CompressedContainer::Zlib) return false;
    if (stream_.avail_in < 2 && file_.remaining() > 0) refill();
    return stream_.avail_in >= 2 && stream_.next_in[0] == 0x1f && stream_.next_in[1] == 0x8b;
}

void InflateStream::refill() {
    // Keep the unread input, append more from the file.
    std::memmove(input_.data(), stream_.next_in == nullptr ? input_.data() : stream_.next_in, stream_.avail_in);
    const std::size_t kept = stream_.avail_in;
    const std::size_t got = file_.read(input_.data() + kept, input_.size() - kept);
    stream_.next_in = input_.data();
    stream_.avail_in = static_cast<uInt>(kept + got);
}

std::size_t InflateStream::read(std::uint8_t* destination, std::size_t count, const std::string& context) {
    std::size_t done = 0;
    while (done < count && !ended_) {
        if (stream_.avail_in == 0) {
            refill();
            if (stream_.avail_in == 0)
                file_.fail("truncated payload: " + context + ", but the " + name() + " stream is cut off after inflating " +
                           std::to_string(produced_) + " bytes");
        }
        const auto window = static_cast<uInt>(std::min<std::size_t>(count - done, std::size_t(1) << 30));
        stream_.next_out = destination + done;
        stream_.avail_out = window;
        const int code = inflate(&stream_, Z_NO_FLUSH);
        check_inflate_result(file_, name(), stream_, code);
        const std::size_t got = window - stream_.avail_out;
        done += got;
        produced_ += got;
        if (code == Z_BUF_ERROR && stream_.avail_in > 0)
            file_.fail("corrupt " + std::string(name()) + " payload: inflate makes no progress");
        if (code == Z_STREAM_END) {
            if (next_member_follows())
                inflateReset(&stream_);
            else
                ended_ = true;
        }
    }
    return done;
}

void InflateStream::skip(std::uint64_t count, const std::string& context) {
    std::uint8_t scratch[4096];
    while (count > 0) {
        const std::size_t piece = static_cast<std::size_t>(std::min<std::uint64_t>(count, sizeof scratch));
        const std::size_t got = read(scratch, piece, context);
        if (got == 0)
            file_.fail("truncated payload: " + context + ", but the " + name() + " stream inflates to only " +
                       std::to_string(produced_) + " bytes");
        count -= got;
    }
}

void InflateStream::decode(std::uint64_t count, SampleWriter& sink, const std::string& context) {
    std::vector<std::uint8_t> output(std::size_t(1) << 18);
    // A box read stops after the box's last slice (bytes_needed).
    while (count > 0 && sink.bytes_needed() > 0) {
        const std::size_t piece = static_cast<std::size_t>(std::min({count, std::uint64_t(output.size()), sink.bytes_needed()}));
        const std::size_t got = read(output.data(), piece, context);
        if (got == 0)
            file_.fail("truncated payload: " + context + ", but the " + name() + " stream inflates to only " +
                       std::to_string(produced_) + " bytes");
        sink.consume(output.data(), got);
        count -= got;
    }
}

std::uint64_t InflateStream::unread_input() const { return stream_.avail_in + file_.remaining(); }

// ----------------------------------------------------------------------------------------------
// Payload checks and decoding

std::uint64_t max_inflated_size(std::uint64_t compressed) {
    if (compressed > (std::numeric_limits<std::uint64_t>::max() - kInflateSlack) / kMaxInflateRatio)
        return std::numeric_limits<std::uint64_t>::max();
    return compressed * kMaxInflateRatio + kInflateSlack;
}

void require_plausible_zlib_payload(const InputFile& file, std::uint64_t expected_bytes, const std::string& description) {
    const std::uint64_t compressed = file.remaining();
    const std::uint64_t max_bytes = max_inflated_size(compressed);
    if (expected_bytes > max_bytes)
        file.fail("truncated or lying header: " + description + ", but the " + std::to_string(compressed) +
                  "-byte zlib payload can inflate to at most " + std::to_string(max_bytes) + " bytes");
}

void decode_zlib_payload(InputFile& file, std::uint64_t expected_bytes, SampleWriter& sink, const std::string& description) {
    InflateStream stream(file, CompressedContainer::Zlib);
    stream.decode(expected_bytes, sink, description);
    if (!sink.complete()) return;  // a box: what follows its last slice is not read
    // Every expected byte is there: the stream may only end now. Probe for one more byte.
    std::uint8_t probe = 0;
    if (stream.read(&probe, 1, description) == 1)
        file.fail("payload larger than header says: " + description + ", but the zlib stream inflates to more than " +
                  std::to_string(expected_bytes) + " bytes");
    const std::uint64_t trailing = stream.unread_input();
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
