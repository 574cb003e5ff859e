#pragma once
// Synthetic datasets for the ml tests: Gaussian blobs with instances (groups) and views.

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "multicue/ml/dataset.hpp"

namespace multicue::test {

/// `classes` Gaussian blobs in `dims` dimensions (centres on a scaled simplex-like pattern),
/// `instances` groups per class with `views` rows each. Blocks of `block_size` columns are named
/// b0, b1, ...; values are shifted to be non-negative so histogram metrics apply.
inline ml::Dataset Blobs(int classes, int instances, int views, int dims, float spread,
                         std::uint32_t seed = 7, int block_size = 0) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> noise(0.0f, spread);
    std::uniform_real_distribution<float> centre(1.0f, 5.0f);
    if (block_size <= 0) block_size = dims;
    std::vector<std::pair<std::string, std::vector<std::string>>> blocks;
    for (int c = 0; c < dims; c += block_size) {
        std::vector<std::string> names;
        for (int j = c; j < std::min(dims, c + block_size); ++j)
            names.push_back(ml::IndexedName("x", static_cast<std::size_t>(j)));
        blocks.push_back({ml::IndexedName("b", static_cast<std::size_t>(c / block_size)), names});
    }
    ml::Dataset d = ml::Dataset::WithBlocks(blocks);
    std::vector<std::vector<float>> centres(static_cast<std::size_t>(classes));
    for (auto& c : centres) {
        c.resize(static_cast<std::size_t>(dims));
        for (auto& v : c) v = centre(rng);
    }
    std::vector<float> row(static_cast<std::size_t>(dims));
    std::int64_t group = 0;
    for (int i = 0; i < instances; ++i) {
        for (int c = 0; c < classes; ++c, ++group) {
            for (int v = 0; v < views; ++v) {
                for (int j = 0; j < dims; ++j) {
                    row[static_cast<std::size_t>(j)] = std::max(
                        0.0f, centres[static_cast<std::size_t>(c)][static_cast<std::size_t>(j)] +
                                  noise(rng));
                }
                d.AppendRow(row,
                            ml::IndexedName("shape", static_cast<std::size_t>(c % 2)) +
                                ml::IndexedName("/class", static_cast<std::size_t>(c)),
                            group, v,
                            ml::IndexedName("g", static_cast<std::size_t>(group)) +
                                ml::IndexedName("_v", static_cast<std::size_t>(v)));
            }
        }
    }
    return d;
}

}  // namespace multicue::test
