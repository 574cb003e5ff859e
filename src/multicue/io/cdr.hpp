#pragma once
/// \file CDR, the serialisation of ROS 2 messages (OMG DDS-XTypes 1.3, section 7.4): a 4-byte
/// encapsulation header (representation identifier and options), then the message's fields in
/// order, each primitive aligned to its own size (at most 8 in plain CDR, at most 4 in CDR2)
/// counted from the end of the header; strings as a uint32 length that includes the terminating
/// NUL, then the bytes and the NUL; sequences as a uint32 element count, then the elements.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace multicue::io {

/// Reads CDR data. Every read checks the remaining bytes and throws FormatError naming `source`
/// and the offset when the data ends early.
class CdrReader {
  public:
    /// Reads the encapsulation header: plain CDR (0x0000 big, 0x0001 little endian) or plain
    /// CDR2 (0x0006, 0x0007). Other representations (parameter lists, delimited CDR2) throw
    /// FormatError.
    CdrReader(std::span<const std::uint8_t> bytes, std::string source);

    bool big_endian() const { return big_endian_; }
    std::uint8_t U8();
    bool Bool() { return U8() != 0; }
    std::int8_t I8() { return static_cast<std::int8_t>(U8()); }
    std::uint16_t U16();
    std::int16_t I16() { return static_cast<std::int16_t>(U16()); }
    std::uint32_t U32();
    std::int32_t I32() { return static_cast<std::int32_t>(U32()); }
    std::uint64_t U64();
    std::int64_t I64() { return static_cast<std::int64_t>(U64()); }
    float F32();
    double F64();
    std::string String();
    /// A sequence's element count, checked against the bytes left (each element at least
    /// `min_element_bytes` long).
    std::uint32_t SequenceLength(std::size_t min_element_bytes);
    /// `n` raw bytes (a uint8[] payload).
    void Bytes(std::size_t n, std::vector<std::uint8_t>& out);

    /// Bytes consumed after the encapsulation header.
    std::size_t position() const { return pos_; }
    std::size_t remaining() const { return body_.size() - pos_; }

  private:
    void Align(std::size_t size);
    /// `size` bytes after aligning to `align` (primitives: their size; byte runs: 1).
    const std::uint8_t* Take(std::size_t size, std::size_t align);

    std::span<const std::uint8_t> body_;
    std::string source_;
    std::size_t pos_ = 0;
    std::size_t max_align_ = 8;
    bool big_endian_ = false;
};

/// Writes plain CDR (little or big endian) with its encapsulation header.
class CdrWriter {
  public:
    explicit CdrWriter(bool big_endian = false);

    void U8(std::uint8_t v);
    void Bool(bool v) { U8(v ? 1 : 0); }
    void U16(std::uint16_t v);
    void U32(std::uint32_t v);
    void I32(std::int32_t v) { U32(static_cast<std::uint32_t>(v)); }
    void U64(std::uint64_t v);
    void F64(double v);
    void String(const std::string& v);
    void Bytes(std::span<const std::uint8_t> v);

    /// The message so far, header included.
    const std::vector<std::uint8_t>& bytes() const { return out_; }

  private:
    void Align(std::size_t size);
    void Put(const void* v, std::size_t size);

    std::vector<std::uint8_t> out_;
    bool big_endian_ = false;
};

}  // namespace multicue::io
