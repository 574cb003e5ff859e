#include "multicue/io/cdr.hpp"

#include <bit>
#include <cstring>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue::io {
namespace {

constexpr std::size_t kHeaderBytes = 4;

/// Reverses the bytes of an unsigned integer (std::byteswap is C++23).
template <typename T>
T SwapBytes(T v) {
    T r = 0;
    for (std::size_t k = 0; k < sizeof(T); ++k)
        r = static_cast<T>((r << 8) | ((v >> (8 * k)) & 0xffu));
    return r;
}

bool SwapFor(bool big_endian) { return big_endian != (std::endian::native == std::endian::big); }

}  // namespace

CdrReader::CdrReader(std::span<const std::uint8_t> bytes, std::string source)
    : source_(std::move(source)) {
    if (bytes.size() < kHeaderBytes) {
        throw FormatError(
            fmt::format("{}: {} bytes, too short for a CDR message", source_, bytes.size()));
    }
    // Representation identifier: big-endian uint16 in the first two bytes.
    const unsigned id = (unsigned{bytes[0]} << 8) | bytes[1];
    switch (id) {
        case 0x0000:  // CDR_BE
        case 0x0001:  // CDR_LE
            max_align_ = 8;
            break;
        case 0x0006:  // CDR2_BE (plain, final types)
        case 0x0007:  // CDR2_LE
            max_align_ = 4;
            break;
        default:
            throw FormatError(fmt::format(
                "{}: CDR representation 0x{:04x} is not supported (plain CDR or CDR2 only)",
                source_, id));
    }
    big_endian_ = (id & 1u) == 0;
    body_ = bytes.subspan(kHeaderBytes);
}

void CdrReader::Align(std::size_t size) {
    const std::size_t a = size < max_align_ ? size : max_align_;
    const std::size_t aligned = (pos_ + a - 1) / a * a;
    if (aligned > body_.size()) {
        throw FormatError(fmt::format("{}: CDR data ends at byte {} (alignment)", source_,
                                      body_.size() + kHeaderBytes));
    }
    pos_ = aligned;
}

const std::uint8_t* CdrReader::Take(std::size_t size, std::size_t align) {
    Align(align);
    if (size > remaining()) {
        throw FormatError(fmt::format("{}: CDR data ends at byte {}, {} more bytes needed at {}",
                                      source_, body_.size() + kHeaderBytes, size,
                                      pos_ + kHeaderBytes));
    }
    const std::uint8_t* p = body_.data() + pos_;
    pos_ += size;
    return p;
}

std::uint8_t CdrReader::U8() { return *Take(1, 1); }

std::uint16_t CdrReader::U16() {
    std::uint16_t v;
    std::memcpy(&v, Take(2, 2), 2);
    return SwapFor(big_endian_) ? SwapBytes(v) : v;
}

std::uint32_t CdrReader::U32() {
    std::uint32_t v;
    std::memcpy(&v, Take(4, 4), 4);
    return SwapFor(big_endian_) ? SwapBytes(v) : v;
}

std::uint64_t CdrReader::U64() {
    std::uint64_t v;
    std::memcpy(&v, Take(8, 8), 8);
    return SwapFor(big_endian_) ? SwapBytes(v) : v;
}

float CdrReader::F32() { return std::bit_cast<float>(U32()); }
double CdrReader::F64() { return std::bit_cast<double>(U64()); }

std::string CdrReader::String() {
    const std::uint32_t length = U32();
    if (length > remaining()) {
        throw FormatError(fmt::format("{}: string of {} bytes at byte {} runs past the end ({})",
                                      source_, length, pos_ + kHeaderBytes,
                                      body_.size() + kHeaderBytes));
    }
    const std::uint8_t* p = Take(length, 1);
    // The length counts the terminating NUL; tolerate writers that leave it out.
    std::size_t n = length;
    if (n > 0 && p[n - 1] == 0) --n;
    return std::string(reinterpret_cast<const char*>(p), n);
}

std::uint32_t CdrReader::SequenceLength(std::size_t min_element_bytes) {
    const std::uint32_t n = U32();
    if (min_element_bytes > 0 && std::uint64_t{n} * min_element_bytes > remaining()) {
        throw FormatError(fmt::format("{}: sequence of {} elements at byte {} runs past the end",
                                      source_, n, pos_ + kHeaderBytes));
    }
    return n;
}

void CdrReader::Bytes(std::size_t n, std::vector<std::uint8_t>& out) {
    if (n > remaining()) {
        throw FormatError(fmt::format("{}: {} bytes at byte {} run past the end ({})", source_, n,
                                      pos_ + kHeaderBytes, body_.size() + kHeaderBytes));
    }
    out.assign(body_.data() + pos_, body_.data() + pos_ + n);
    pos_ += n;
}

CdrWriter::CdrWriter(bool big_endian) : big_endian_(big_endian) {
    out_ = {0x00, static_cast<std::uint8_t>(big_endian ? 0x00 : 0x01), 0x00, 0x00};
}

void CdrWriter::Align(std::size_t size) {
    while ((out_.size() - kHeaderBytes) % size != 0) out_.push_back(0);
}

void CdrWriter::Put(const void* v, std::size_t size) {
    Align(size);
    const auto* b = static_cast<const std::uint8_t*>(v);
    for (std::size_t k = 0; k < size; ++k)
        out_.push_back(SwapFor(big_endian_) ? b[size - 1 - k] : b[k]);
}

void CdrWriter::U8(std::uint8_t v) { out_.push_back(v); }
void CdrWriter::U16(std::uint16_t v) { Put(&v, 2); }
void CdrWriter::U32(std::uint32_t v) { Put(&v, 4); }
void CdrWriter::U64(std::uint64_t v) { Put(&v, 8); }
void CdrWriter::F64(double v) { Put(&v, 8); }

void CdrWriter::String(const std::string& v) {
    U32(static_cast<std::uint32_t>(v.size() + 1));
    out_.insert(out_.end(), v.begin(), v.end());
    out_.push_back(0);
}

void CdrWriter::Bytes(std::span<const std::uint8_t> v) {
    out_.insert(out_.end(), v.begin(), v.end());
}

}  // namespace multicue::io
