#pragma once
/// \file Internals shared by the PLY reader (ply_read.cpp) and writer (ply_write.cpp): the scalar
/// types of PLY properties and their mapping to extra fields.

#include <cstddef>
#include <cstdint>
#include <string>

#include "multicue/core/point_cloud.hpp"

namespace multicue::io::detail {

enum class ScalarType : std::uint8_t {
    kInt8,
    kUint8,
    kInt16,
    kUint16,
    kInt32,
    kUint32,
    kFloat32,
    kFloat64
};

/// Calls f(T{}) with the C++ type T of `t`.
template <typename F>
decltype(auto) WithType(ScalarType t, F&& f) {
    switch (t) {
        case ScalarType::kInt8:
            return f(std::int8_t{});
        case ScalarType::kUint8:
            return f(std::uint8_t{});
        case ScalarType::kInt16:
            return f(std::int16_t{});
        case ScalarType::kUint16:
            return f(std::uint16_t{});
        case ScalarType::kInt32:
            return f(std::int32_t{});
        case ScalarType::kUint32:
            return f(std::uint32_t{});
        case ScalarType::kFloat32:
            return f(float{});
        case ScalarType::kFloat64:
            break;
    }
    return f(double{});
}

inline std::size_t SizeOf(ScalarType t) {
    return WithType(t, [](auto v) { return sizeof(v); });
}

inline bool IsFloat(ScalarType t) { return t == ScalarType::kFloat32 || t == ScalarType::kFloat64; }

/// The classic names, which every PLY reader (PCL's included) understands.
inline const char* TypeName(ScalarType t) {
    static constexpr const char* kNames[] = {"char", "uchar", "short", "ushort",
                                             "int",  "uint",  "float", "double"};
    return kNames[static_cast<int>(t)];
}

inline bool IsSpace(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

/// The extra field that keeps a scalar property of type `t`: 'F', 'I' or 'U' of the type's size.
inline ExtraField MakeExtraField(const std::string& name, ScalarType t) {
    const bool is_signed =
        t == ScalarType::kInt8 || t == ScalarType::kInt16 || t == ScalarType::kInt32;
    return ExtraField{name,
                      IsFloat(t)  ? 'F'
                      : is_signed ? 'I'
                                  : 'U',
                      static_cast<std::uint8_t>(SizeOf(t)),
                      1,
                      {}};
}

}  // namespace multicue::io::detail
