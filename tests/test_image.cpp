// PNG and JPEG textures (io::ReadRgbImage): decoded pixels against what was encoded, grey and alpha
// images, truncated and foreign files, and the area-averaging shrink.

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <jpeglib.h>
#include <png.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/image.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

// A w x h image of `channels` (1 grey, 3 RGB, 4 RGBA) with distinct smooth values.
std::vector<std::uint8_t> Pattern(int w, int h, int channels) {
    std::vector<std::uint8_t> px(static_cast<std::size_t>(w * h * channels));
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            for (int c = 0; c < channels; ++c) {
                px[static_cast<std::size_t>((y * w + x) * channels + c)] =
                    static_cast<std::uint8_t>((x * 7 + y * 3 + c * 60) % 256);
            }
        }
    }
    return px;
}

std::string EncodePng(const std::vector<std::uint8_t>& px, int w, int h, int channels) {
    png_image png;
    std::memset(&png, 0, sizeof(png));
    png.version = PNG_IMAGE_VERSION;
    png.width = static_cast<png_uint_32>(w);
    png.height = static_cast<png_uint_32>(h);
    png.format = channels == 1 ? PNG_FORMAT_GRAY : channels == 3 ? PNG_FORMAT_RGB : PNG_FORMAT_RGBA;
    png_alloc_size_t size = 0;
    EXPECT_NE(png_image_write_to_memory(&png, nullptr, &size, 0, px.data(), 0, nullptr), 0);
    std::string out(size, '\0');
    EXPECT_NE(png_image_write_to_memory(&png, out.data(), &size, 0, px.data(), 0, nullptr), 0);
    out.resize(size);
    return out;
}

std::string EncodeJpeg(const std::vector<std::uint8_t>& px, int w, int h, int channels) {
    jpeg_compress_struct info;
    jpeg_error_mgr error;
    info.err = jpeg_std_error(&error);
    jpeg_create_compress(&info);
    unsigned char* buffer = nullptr;
    unsigned long size = 0;
    jpeg_mem_dest(&info, &buffer, &size);
    info.image_width = static_cast<JDIMENSION>(w);
    info.image_height = static_cast<JDIMENSION>(h);
    info.input_components = channels;
    info.in_color_space = channels == 1 ? JCS_GRAYSCALE : JCS_RGB;
    jpeg_set_defaults(&info);
    jpeg_set_quality(&info, 100, TRUE);
    jpeg_start_compress(&info, TRUE);
    while (info.next_scanline < info.image_height) {
        auto* row = const_cast<JSAMPLE*>(px.data() + std::size_t{info.next_scanline} *
                                                         static_cast<std::size_t>(w * channels));
        jpeg_write_scanlines(&info, &row, 1);
    }
    jpeg_finish_compress(&info);
    jpeg_destroy_compress(&info);
    std::string out(reinterpret_cast<char*>(buffer), size);
    std::free(buffer);
    return out;
}

std::filesystem::path Write(const test::TempDir& dir, const std::string& name,
                            const std::string& bytes) {
    const auto path = dir / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
}

TEST(Image, PngPixelsAreExact) {
    test::TempDir dir;
    const int w = 37, h = 23;
    for (int channels : {1, 3, 4}) {
        const auto px = Pattern(w, h, channels);
        const io::RgbImage img =
            io::ReadRgbImage(Write(dir, "t.png", EncodePng(px, w, h, channels)));
        ASSERT_EQ(img.width, static_cast<std::uint32_t>(w));
        ASSERT_EQ(img.height, static_cast<std::uint32_t>(h));
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w; ++x) {
                const Color& c =
                    img.At(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y));
                const std::size_t k = static_cast<std::size_t>((y * w + x) * channels);
                // Grey is spread over the three channels; alpha is dropped, not composed.
                EXPECT_EQ(c.r, px[k]);
                EXPECT_EQ(c.g, px[k + (channels == 1 ? 0 : 1)]);
                EXPECT_EQ(c.b, px[k + (channels == 1 ? 0 : 2)]);
                EXPECT_EQ(c.a, 255);
            }
        }
    }
}

TEST(Image, JpegPixelsAreCloseAndTopRowFirst) {
    test::TempDir dir;
    const int w = 40, h = 24;
    for (int channels : {1, 3}) {
        std::vector<std::uint8_t> px(static_cast<std::size_t>(w * h * channels));
        // Bright top half, dark bottom half: a flipped decode would be far off.
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w * channels; ++x) {
                px[static_cast<std::size_t>(y * w * channels + x)] =
                    static_cast<std::uint8_t>(y < h / 2 ? 220 : 30);
            }
        }
        const io::RgbImage img =
            io::ReadRgbImage(Write(dir, "t.jpg", EncodeJpeg(px, w, h, channels)));
        ASSERT_EQ(img.width, static_cast<std::uint32_t>(w));
        ASSERT_EQ(img.height, static_cast<std::uint32_t>(h));
        for (std::uint32_t y = 0; y < img.height; ++y) {
            for (std::uint32_t x = 0; x < img.width; ++x) {
                const int want = y < img.height / 2 ? 220 : 30;
                const Color& c = img.At(x, y);
                EXPECT_NEAR(c.r, want, 6);
                EXPECT_NEAR(c.g, want, 6);
                EXPECT_NEAR(c.b, want, 6);
            }
        }
    }
}

TEST(Image, TruncatedForeignAndMissingFilesThrow) {
    test::TempDir dir;
    const auto rgb = Pattern(64, 48, 3);
    const std::string png = EncodePng(rgb, 64, 48, 3);
    const std::string jpg = EncodeJpeg(rgb, 64, 48, 3);
    EXPECT_THROW(io::ReadRgbImage(dir / "none.png"), IoError);
    EXPECT_THROW(io::ReadRgbImage(Write(dir, "junk.png", "not an image")), FormatError);
    EXPECT_THROW(io::ReadRgbImage(Write(dir, "empty.png", "")), FormatError);
    EXPECT_THROW(io::ReadRgbImage(Write(dir, "half.png", png.substr(0, png.size() / 2))),
                 FormatError);
    EXPECT_THROW(io::ReadRgbImage(Write(dir, "head.png", png.substr(0, 20))), FormatError);
    EXPECT_THROW(io::ReadRgbImage(Write(dir, "half.jpg", jpg.substr(0, jpg.size() / 2))),
                 FormatError);
    EXPECT_THROW(io::ReadRgbImage(Write(dir, "head.jpg", jpg.substr(0, 4))), FormatError);
    // A BMP header: a format that is not read.
    EXPECT_THROW(io::ReadRgbImage(Write(dir, "t.bmp", std::string("BM") + std::string(60, '\0'))),
                 FormatError);
    // The whole files still decode.
    EXPECT_EQ(io::ReadRgbImage(Write(dir, "ok.png", png)).width, 64u);
    EXPECT_EQ(io::ReadRgbImage(Write(dir, "ok.jpg", jpg)).height, 48u);
}

TEST(Image, ShrinkAverages) {
    io::RgbImage img;
    img.width = 4;
    img.height = 2;
    for (int i = 0; i < 8; ++i) {
        img.pixels.push_back(i % 2 == 0 ? Color{200, 0, 0, 255} : Color{0, 0, 200, 255});
    }
    const io::RgbImage s = io::ShrinkImage(img, 1);
    ASSERT_EQ(s.width, 1u);
    ASSERT_EQ(s.height, 1u);
    EXPECT_NEAR(s.pixels[0].r, 100, 2);
    EXPECT_NEAR(s.pixels[0].b, 100, 2);
    const io::RgbImage same = io::ShrinkImage(img, 4);
    EXPECT_EQ(same.width, 4u);
    EXPECT_EQ(same.pixels[1].b, 200);
    EXPECT_THROW(io::ShrinkImage(img, 0), InvalidArgument);
}

}  // namespace
}  // namespace multicue
