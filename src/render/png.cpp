// PNG files through libpng: RGB, 8 bits per channel.

#include <tetcut/error.hpp>
#include <tetcut/render.hpp>

#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <memory>

namespace tetcut::render {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

}  // namespace

void write_png(const std::filesystem::path& path, const Image& image) {
  if (image.width < 1 || image.height < 1 || image.rgb.size() != 3u * image.width * image.height) {
    throw Error(ErrorKind::kInvalidArgument, "the image is empty or its pixels do not match its size", path.string());
  }
  // Written beside the target and renamed into place, like every writer here.
  const std::filesystem::path temporary = path.string() + ".tmp";
  {
    File file(std::fopen(temporary.c_str(), "wb"));
    if (!file) throw Error(ErrorKind::kIo, "cannot open for writing", path.string());
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    if (png == nullptr || info == nullptr || setjmp(png_jmpbuf(png))) {
      png_destroy_write_struct(&png, &info);
      std::filesystem::remove(temporary);
      throw Error(ErrorKind::kIo, "could not write the PNG", path.string());
    }
    png_init_io(png, file.get());
    png_set_IHDR(png, info, static_cast<png_uint_32>(image.width), static_cast<png_uint_32>(image.height), 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (int y = 0; y < image.height; ++y) {
      png_write_row(png, image.rgb.data() + 3 * static_cast<std::size_t>(y) * image.width);
    }
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    if (std::fflush(file.get()) != 0) throw Error(ErrorKind::kIo, "could not write the PNG", path.string());
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) throw Error(ErrorKind::kIo, "cannot rename into place: " + error.message(), path.string());
}

Image read_png(const std::filesystem::path& path) {
  File file(std::fopen(path.c_str(), "rb"));
  if (!file) throw Error(ErrorKind::kIo, "cannot open", path.string());
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  Image image;
  if (png == nullptr || info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw Error(ErrorKind::kInvalidInput, "not a readable PNG", path.string());
  }
  png_init_io(png, file.get());
  png_read_info(png, info);
  // Any PNG becomes 8-bit RGB.
  png_set_expand(png);
  png_set_strip_16(png);
  png_set_strip_alpha(png);
  png_set_gray_to_rgb(png);
  png_read_update_info(png, info);
  image.width = static_cast<int>(png_get_image_width(png, info));
  image.height = static_cast<int>(png_get_image_height(png, info));
  image.rgb.resize(3 * static_cast<std::size_t>(image.width) * image.height);
  for (int y = 0; y < image.height; ++y) png_read_row(png, image.rgb.data() + 3 * static_cast<std::size_t>(y) * image.width, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return image;
}

}  // namespace tetcut::render
