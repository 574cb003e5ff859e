#pragma once
/// \file The storage readers behind OpenRos2Bag (bag.cpp): rosbag2's SQLite storage
/// (bag_sqlite.cpp) and MCAP (bag_mcap.cpp).

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "multicue/io/bag.hpp"

namespace multicue::io::detail {

std::unique_ptr<BagReader> OpenSqliteBag(const std::filesystem::path& path,
                                         const std::vector<std::string>& topics);
std::unique_ptr<BagReader> OpenMcapBag(const std::filesystem::path& path,
                                       const std::vector<std::string>& topics);

/// rosbag2 may store each message zstd-compressed (compression_mode: message); returns the
/// decompressed bytes when `data` is a zstd frame, else leaves it as it is. Throws FormatError
/// naming `source` for a corrupt frame or a build without zstd.
void DecompressIfZstd(std::vector<std::uint8_t>& data, const std::string& source);

/// Decompresses an MCAP chunk ("zstd" or "lz4" frame) of known size.
std::vector<std::uint8_t> Decompress(const std::string& compression,
                                     std::span<const std::uint8_t> data, std::uint64_t size,
                                     const std::string& source);

}  // namespace multicue::io::detail
