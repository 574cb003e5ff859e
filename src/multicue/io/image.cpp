#include "multicue/io/image.hpp"

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <cstring>

#include <fmt/format.h>
#include <jerror.h>
#include <jpeglib.h>
#include <png.h>
#include <opencv2/imgproc.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"

namespace multicue::io {
namespace {

// Decoded images larger than this are refused before any pixel memory is taken (a corrupt header
// must not ask for gigabytes); 8192 x 8192 is more than any texture of the mesh formats read.
constexpr std::uint64_t kMaxPixels = std::uint64_t{8192} * 8192;

bool IsPng(const std::string& bytes) {
    return bytes.size() >= 8 &&
           png_sig_cmp(reinterpret_cast<png_const_bytep>(bytes.data()), 0, 8) == 0;
}

bool IsJpeg(const std::string& bytes) {
    return bytes.size() >= 3 && static_cast<unsigned char>(bytes[0]) == 0xFF &&
           static_cast<unsigned char>(bytes[1]) == 0xD8 &&
           static_cast<unsigned char>(bytes[2]) == 0xFF;
}

bool DecodableSize(std::uint64_t width, std::uint64_t height) {
    return width > 0 && height > 0 && width * height <= kMaxPixels;
}

// libpng's simplified API: every colour type and bit depth converted to 8-bit RGBA; the alpha
// channel is dropped.
RgbImage DecodePng(const std::filesystem::path& path, const std::string& bytes) {
    png_image png;
    std::memset(&png, 0, sizeof(png));
    png.version = PNG_IMAGE_VERSION;
    if (png_image_begin_read_from_memory(&png, bytes.data(), bytes.size()) == 0) {
        const std::string message = png.message;
        png_image_free(&png);
        throw FormatError(fmt::format("{}: cannot decode PNG: {}", path.string(), message));
    }
    if (!DecodableSize(png.width, png.height)) {
        png_image_free(&png);
        throw FormatError(fmt::format("{}: cannot decode PNG: {} x {} pixels", path.string(),
                                      png.width, png.height));
    }
    png.format = PNG_FORMAT_RGBA;
    std::vector<std::uint8_t> rgba(PNG_IMAGE_SIZE(png));
    if (png_image_finish_read(&png, nullptr, rgba.data(), 0, nullptr) == 0) {
        const std::string message = png.message;
        png_image_free(&png);
        throw FormatError(fmt::format("{}: cannot decode PNG: {}", path.string(), message));
    }
    RgbImage out;
    out.width = png.width;
    out.height = png.height;
    png_image_free(&png);
    out.pixels.resize(std::size_t{out.width} * out.height);
    for (std::size_t i = 0; i < out.pixels.size(); ++i) {
        out.pixels[i] = Color{rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2], 255};
    }
    return out;
}

// libjpeg reports fatal errors through error_exit, which must not return: it jumps back to the
// decoder with the message saved.
struct JpegError {
    jpeg_error_mgr manager;
    std::jmp_buf jump;
    char message[JMSG_LENGTH_MAX];
};

void JpegErrorExit(j_common_ptr info) {
    auto* error = reinterpret_cast<JpegError*>(info->err);
    (*info->err->format_message)(info, error->message);
    std::longjmp(error->jump, 1);
}

// A premature end of the data is fatal too (libjpeg only warns and fills the rest with grey): a
// texture decoded from half a file would colour the scans silently wrong. Other warnings (extra
// bytes before a marker, common in camera files) are ignored, as other decoders do.
void JpegEmitMessage(j_common_ptr info, int level) {
    if (level < 0 && info->err->msg_code == JWRN_JPEG_EOF) JpegErrorExit(info);
}

// Decodes into `rgb`; false with the reason in error.message. No object with a destructor lives
// in this frame between setjmp and the jumps back to it.
bool DecodeJpegInto(const std::string& bytes, JpegError& error, std::vector<std::uint8_t>& rgb,
                    std::uint32_t& width, std::uint32_t& height) {
    jpeg_decompress_struct info;
    info.err = jpeg_std_error(&error.manager);
    error.manager.error_exit = JpegErrorExit;
    error.manager.emit_message = JpegEmitMessage;
    if (setjmp(error.jump) != 0) {
        jpeg_destroy_decompress(&info);
        return false;
    }
    jpeg_create_decompress(&info);
    jpeg_mem_src(&info, reinterpret_cast<const unsigned char*>(bytes.data()),
                 static_cast<unsigned long>(bytes.size()));
    jpeg_read_header(&info, TRUE);
    const bool cmyk = info.jpeg_color_space == JCS_CMYK || info.jpeg_color_space == JCS_YCCK;
    if (cmyk || !DecodableSize(info.image_width, info.image_height)) {
        if (cmyk) {
            std::snprintf(error.message, sizeof(error.message), "CMYK images are not supported");
        } else {
            std::snprintf(error.message, sizeof(error.message), "%u x %u pixels", info.image_width,
                          info.image_height);
        }
        jpeg_destroy_decompress(&info);
        return false;
    }
    info.out_color_space = JCS_RGB;
    jpeg_start_decompress(&info);
    width = info.output_width;
    height = info.output_height;
    rgb.resize(std::size_t{width} * height * 3);
    while (info.output_scanline < info.output_height) {
        JSAMPROW row = rgb.data() + std::size_t{info.output_scanline} * width * 3;
        jpeg_read_scanlines(&info, &row, 1);
    }
    jpeg_finish_decompress(&info);
    jpeg_destroy_decompress(&info);
    return true;
}

RgbImage DecodeJpeg(const std::filesystem::path& path, const std::string& bytes) {
    JpegError error{};
    std::vector<std::uint8_t> rgb;
    std::uint32_t width = 0, height = 0;
    if (!DecodeJpegInto(bytes, error, rgb, width, height)) {
        throw FormatError(fmt::format("{}: cannot decode JPEG: {}", path.string(), error.message));
    }
    RgbImage out;
    out.width = width;
    out.height = height;
    out.pixels.resize(std::size_t{width} * height);
    for (std::size_t i = 0; i < out.pixels.size(); ++i) {
        out.pixels[i] = Color{rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2], 255};
    }
    return out;
}

}  // namespace

RgbImage ReadRgbImage(const std::filesystem::path& path) {
    const std::string bytes = ReadFileBytes(path);
    if (IsPng(bytes)) return DecodePng(path, bytes);
    if (IsJpeg(bytes)) return DecodeJpeg(path, bytes);
    throw FormatError(
        fmt::format("{}: cannot decode image: not a PNG or JPEG file", path.string()));
}

RgbImage ShrinkImage(const RgbImage& image, std::uint32_t max_side) {
    if (max_side == 0) throw InvalidArgument("ShrinkImage: max_side must be > 0");
    if (image.width <= max_side && image.height <= max_side) return image;
    const double f = static_cast<double>(max_side) / std::max(image.width, image.height);
    const int w = std::max(1, static_cast<int>(image.width * f + 0.5));
    const int h = std::max(1, static_cast<int>(image.height * f + 0.5));
    cv::Mat rgb(static_cast<int>(image.height), static_cast<int>(image.width), CV_8UC3);
    for (std::uint32_t y = 0; y < image.height; ++y) {
        auto* row = rgb.ptr<cv::Vec3b>(static_cast<int>(y));
        for (std::uint32_t x = 0; x < image.width; ++x) {
            const Color& c = image.At(x, y);
            row[x] = cv::Vec3b(c.r, c.g, c.b);
        }
    }
    cv::Mat small;
    cv::resize(rgb, small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
    RgbImage out;
    out.width = static_cast<std::uint32_t>(small.cols);
    out.height = static_cast<std::uint32_t>(small.rows);
    out.pixels.resize(std::size_t{out.width} * out.height);
    for (int y = 0; y < small.rows; ++y) {
        const auto* row = small.ptr<cv::Vec3b>(y);
        for (int x = 0; x < small.cols; ++x) {
            out.pixels[static_cast<std::size_t>(y) * out.width + static_cast<std::size_t>(x)] =
                Color{row[x][0], row[x][1], row[x][2], 255};
        }
    }
    return out;
}

}  // namespace multicue::io
