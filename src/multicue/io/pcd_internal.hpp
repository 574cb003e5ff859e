#pragma once
/// \file Internals shared by the PCD reader (pcd_read.cpp) and writer (pcd_write.cpp): the scalar
/// types of PCD fields and strided copies between field buffers.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <type_traits>

#include "multicue/core/point_cloud.hpp"

namespace multicue::io::detail {

// PCD binary data is in the writer's byte order, which is little endian for every file PCL writes.
static_assert(std::endian::native == std::endian::little, "the PCD reader assumes little endian");
static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "points must be packed xyz floats");

using Byte = std::uint8_t;

enum class Scalar : std::uint8_t { kI8, kU8, kI16, kU16, kI32, kU32, kI64, kU64, kF32, kF64 };

inline std::optional<Scalar> ScalarOf(char type, unsigned size) {
    switch (type) {
        case 'F':
            return size == 4 ? Scalar::kF32 : size == 8 ? Scalar::kF64 : std::optional<Scalar>{};
        case 'I':
            return size == 1   ? Scalar::kI8
                   : size == 2 ? Scalar::kI16
                   : size == 4 ? Scalar::kI32
                   : size == 8 ? Scalar::kI64
                               : std::optional<Scalar>{};
        case 'U':
            return size == 1   ? Scalar::kU8
                   : size == 2 ? Scalar::kU16
                   : size == 4 ? Scalar::kU32
                   : size == 8 ? Scalar::kU64
                               : std::optional<Scalar>{};
        default:
            return {};
    }
}

/// Calls fn(T{}) with the C++ type of a PCD scalar, so that loops are instantiated per type.
template <typename Fn>
void VisitScalar(Scalar s, Fn&& fn) {
    switch (s) {
        case Scalar::kI8:
            return fn(std::int8_t{});
        case Scalar::kU8:
            return fn(std::uint8_t{});
        case Scalar::kI16:
            return fn(std::int16_t{});
        case Scalar::kU16:
            return fn(std::uint16_t{});
        case Scalar::kI32:
            return fn(std::int32_t{});
        case Scalar::kU32:
            return fn(std::uint32_t{});
        case Scalar::kI64:
            return fn(std::int64_t{});
        case Scalar::kU64:
            return fn(std::uint64_t{});
        case Scalar::kF32:
            return fn(float{});
        case Scalar::kF64:
            return fn(double{});
    }
}

/// Copies `bytes` bytes per element for n elements between strided buffers.
inline void CopyStrided(const Byte* src, std::size_t src_stride, Byte* dst, std::size_t dst_stride,
                        std::size_t bytes, std::size_t n) {
    if (src_stride == bytes && dst_stride == bytes) {
        if (n > 0) std::memcpy(dst, src, n * bytes);
        return;
    }
    const auto loop = [&](auto constant_bytes) {
        for (std::size_t i = 0; i < n; ++i) {
            std::memcpy(dst + i * dst_stride, src + i * src_stride, constant_bytes);
        }
    };
    // Constant sizes let the compiler turn each memcpy into one load and store.
    switch (bytes) {
        case 1:
            return loop(std::integral_constant<std::size_t, 1>{});
        case 2:
            return loop(std::integral_constant<std::size_t, 2>{});
        case 4:
            return loop(std::integral_constant<std::size_t, 4>{});
        case 8:
            return loop(std::integral_constant<std::size_t, 8>{});
        case 12:
            return loop(std::integral_constant<std::size_t, 12>{});
        default:
            return loop(bytes);
    }
}

}  // namespace multicue::io::detail
