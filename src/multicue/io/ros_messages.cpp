#include "multicue/io/ros_messages.hpp"

#include <bit>
#include <cstring>
#include <type_traits>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/cdr.hpp"

namespace multicue::io {
namespace {

static_assert(std::endian::native == std::endian::little,
              "ROS 1 serialisation is read as little endian");

/// Padding a writer may leave after the last field (alignment of the whole message).
constexpr std::size_t kMaxTrailingBytes = 7;

/// ROS 1 serialisation: little endian, packed, strings and arrays prefixed by a uint32 length.
class Ros1Reader {
  public:
    Ros1Reader(std::span<const std::uint8_t> bytes, const std::string& source)
        : bytes_(bytes), source_(source) {}

    const std::uint8_t* Take(std::size_t n) {
        if (n > bytes_.size() - pos_) {
            throw FormatError(fmt::format("{}: message ends at byte {}, {} more bytes needed at {}",
                                          source_, bytes_.size(), n, pos_));
        }
        const std::uint8_t* p = bytes_.data() + pos_;
        pos_ += n;
        return p;
    }
    std::uint8_t U8() { return *Take(1); }
    std::uint32_t U32() {
        std::uint32_t v;
        std::memcpy(&v, Take(4), 4);
        return v;
    }
    std::string String() {
        const std::uint32_t n = U32();
        const std::uint8_t* p = Take(n);
        return std::string(reinterpret_cast<const char*>(p), n);
    }
    std::size_t remaining() const { return bytes_.size() - pos_; }

  private:
    std::span<const std::uint8_t> bytes_;
    const std::string& source_;
    std::size_t pos_ = 0;
};

class Ros1Writer {
  public:
    void U8(std::uint8_t v) { out.push_back(v); }
    void U32(std::uint32_t v) {
        const auto* b = reinterpret_cast<const std::uint8_t*>(&v);
        out.insert(out.end(), b, b + 4);
    }
    void String(const std::string& s) {
        U32(static_cast<std::uint32_t>(s.size()));
        out.insert(out.end(), s.begin(), s.end());
    }
    std::vector<std::uint8_t> out;
};

/// The body after the header, the same field order in both serialisations.
template <typename Reader>
void ReadCloudBody(Reader& r, PointCloud2Message& m, std::size_t field_min_bytes) {
    m.height = r.U32();
    m.width = r.U32();
    std::uint32_t nfields = 0;
    if constexpr (std::is_same_v<Reader, CdrReader>) {
        nfields = r.SequenceLength(field_min_bytes);
    } else {
        nfields = r.U32();
        if (std::uint64_t{nfields} * field_min_bytes > r.remaining()) {
            throw FormatError(fmt::format("{} fields do not fit the message", nfields));
        }
    }
    m.fields.resize(nfields);
    for (auto& f : m.fields) {
        f.name = r.String();
        f.offset = r.U32();
        f.datatype = r.U8();
        f.count = r.U32();
    }
    m.is_bigendian = r.U8() != 0;
    m.point_step = r.U32();
    m.row_step = r.U32();
}

}  // namespace

bool IsPointCloud2Type(const std::string& type) {
    return type == kPointCloud2Ros2Type || type == kPointCloud2Ros1Type;
}

PointCloud2Message DecodePointCloud2Cdr(std::span<const std::uint8_t> bytes,
                                        const std::string& source) {
    CdrReader r(bytes, source);
    PointCloud2Message m;
    m.stamp.sec = r.I32();
    m.stamp.nanosec = r.U32();
    m.frame_id = r.String();
    // A field: name (4 + 1 bytes at least), offset, datatype, count.
    ReadCloudBody(r, m, 4 + 1 + 4 + 1 + 4);
    const std::uint32_t n = r.SequenceLength(1);
    r.Bytes(n, m.data);
    m.is_dense = r.Bool();
    if (r.remaining() > kMaxTrailingBytes) {
        throw FormatError(
            fmt::format("{}: {} bytes left after the PointCloud2 (not a "
                        "sensor_msgs/msg/PointCloud2?)",
                        source, r.remaining()));
    }
    return m;
}

std::vector<std::uint8_t> EncodePointCloud2Cdr(const PointCloud2Message& m, bool big_endian) {
    CdrWriter w(big_endian);
    w.I32(static_cast<std::int32_t>(m.stamp.sec));
    w.U32(m.stamp.nanosec);
    w.String(m.frame_id);
    w.U32(m.height);
    w.U32(m.width);
    w.U32(static_cast<std::uint32_t>(m.fields.size()));
    for (const auto& f : m.fields) {
        w.String(f.name);
        w.U32(f.offset);
        w.U8(f.datatype);
        w.U32(f.count);
    }
    w.Bool(m.is_bigendian);
    w.U32(m.point_step);
    w.U32(m.row_step);
    w.U32(static_cast<std::uint32_t>(m.data.size()));
    w.Bytes(m.data);
    w.Bool(m.is_dense);
    return w.bytes();
}

PointCloud2Message DecodePointCloud2Ros1(std::span<const std::uint8_t> bytes,
                                         const std::string& source) {
    Ros1Reader r(bytes, source);
    PointCloud2Message m;
    try {
        m.seq = r.U32();
        m.stamp.sec = r.U32();
        m.stamp.nanosec = r.U32();
        m.frame_id = r.String();
        ReadCloudBody(r, m, 4 + 4 + 1 + 4);
        const std::uint32_t n = r.U32();
        const std::uint8_t* p = r.Take(n);
        m.data.assign(p, p + n);
        m.is_dense = r.U8() != 0;
    } catch (const FormatError& e) {
        const std::string what = e.what();
        if (what.rfind(source, 0) == 0) throw;
        throw FormatError(source + ": " + what);
    }
    if (r.remaining() != 0) {
        throw FormatError(
            fmt::format("{}: {} bytes left after the PointCloud2 (not a sensor_msgs/PointCloud2?)",
                        source, r.remaining()));
    }
    return m;
}

std::vector<std::uint8_t> EncodePointCloud2Ros1(const PointCloud2Message& m) {
    Ros1Writer w;
    w.U32(m.seq);
    w.U32(static_cast<std::uint32_t>(m.stamp.sec));
    w.U32(m.stamp.nanosec);
    w.String(m.frame_id);
    w.U32(m.height);
    w.U32(m.width);
    w.U32(static_cast<std::uint32_t>(m.fields.size()));
    for (const auto& f : m.fields) {
        w.String(f.name);
        w.U32(f.offset);
        w.U8(f.datatype);
        w.U32(f.count);
    }
    w.U8(m.is_bigendian ? 1 : 0);
    w.U32(m.point_step);
    w.U32(m.row_step);
    w.U32(static_cast<std::uint32_t>(m.data.size()));
    w.out.insert(w.out.end(), m.data.begin(), m.data.end());
    w.U8(m.is_dense ? 1 : 0);
    return std::move(w.out);
}

std::string DecodeStringCdr(std::span<const std::uint8_t> bytes, const std::string& source) {
    CdrReader r(bytes, source);
    std::string s = r.String();
    if (r.remaining() > kMaxTrailingBytes) {
        throw FormatError(fmt::format("{}: {} bytes left after the string", source, r.remaining()));
    }
    return s;
}

}  // namespace multicue::io
