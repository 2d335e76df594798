/*
 * H-SLAM for ViSP.
 */
#include "io/ImageCodec.h"

#include <visp3/core/vpImageConvert.h>

#include <cctype>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

#include <jpeglib.h>
#include <png.h>

namespace hslam
{
namespace io
{
namespace
{
//! Room for a libjpeg / libpng error message.
constexpr std::size_t kMessageSize = 200;
//! Largest side accepted, pixels: a corrupt header must not ask for terabytes.
constexpr unsigned long kMaxSide = 1u << 16;
//! Largest image accepted, pixels (8192 x 8192): two sides under kMaxSide still multiply to 4 G pixels, which a
//! corrupt or hostile header would make us allocate before the data is read. No camera this library serves comes near.
constexpr unsigned long long kMaxPixels = 1ull << 26;

//! Whether a header's size is one we decode (each side and the product).
bool imageSizeAccepted(unsigned long width, unsigned long height)
{
  return width > 0 && height > 0 && width <= kMaxSide && height <= kMaxSide &&
         static_cast<unsigned long long>(width) * height <= kMaxPixels;
}
//! 16-bit colour PNM files (rare): OpenCV's fixed-point BT.601 weights (cvtColor BGR2GRAY), (R, G, B) / 2^14.
constexpr unsigned kGreyWeightR = 4899, kGreyWeightG = 9617, kGreyWeightB = 1868, kGreyShift = 14;

[[noreturn]] void fail(const std::string &name, const std::string &what)
{
  throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot decode image '" + name + "': " + what);
}

//! Copy \e in into \e out (kMessageSize bytes), cut if longer, always terminated.
void copyMessage(char *out, const char *in)
{
  const std::size_t n = strnlen(in, kMessageSize - 1);
  std::memcpy(out, in, n);
  out[n] = '\0';
}

// ---- JPEG (libjpeg). The error handler jumps back with the message; warnings (corrupt data that libjpeg
// recovers from) stay silent, a library does not print.

struct JpegErrorHandler {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void jpegErrorExit(j_common_ptr cinfo)
{
  JpegErrorHandler *handler = reinterpret_cast<JpegErrorHandler *>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, handler->message);
  std::longjmp(handler->jump, 1);
}

void jpegSilent(j_common_ptr) {}

//! Grey output straight from libjpeg (its Y channel for colour files), as OpenCV's IMREAD_GRAYSCALE asks.
bool decodeJpeg(const unsigned char *data, std::size_t size, vpImage<unsigned char> &I, char *message)
{
  jpeg_decompress_struct cinfo;
  JpegErrorHandler handler;
  cinfo.err = jpeg_std_error(&handler.manager);
  handler.manager.error_exit = jpegErrorExit;
  handler.manager.output_message = jpegSilent;
  if (setjmp(handler.jump) != 0) {
    copyMessage(message, handler.message);
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, data, static_cast<unsigned long>(size));
  jpeg_read_header(&cinfo, TRUE);
  if (cinfo.num_components == 4) {
    copyMessage(message, "CMYK JPEG files are not supported");
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  cinfo.out_color_space = JCS_GRAYSCALE;
  cinfo.out_color_components = 1;
  jpeg_start_decompress(&cinfo);
  if (!imageSizeAccepted(cinfo.output_width, cinfo.output_height)) {
    copyMessage(message, "bad image size in the JPEG header");
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  I.resize(cinfo.output_height, cinfo.output_width);
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = I[cinfo.output_scanline];
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  return true;
}

// ---- PNG (libpng), read from memory.

struct PngSource {
  const unsigned char *data;
  std::size_t size;
  std::size_t offset;
};

void pngRead(png_structp png, png_bytep out, png_size_t n)
{
  PngSource *source = static_cast<PngSource *>(png_get_io_ptr(png));
  if (n > source->size - source->offset) {
    png_error(png, "the PNG data ends early (truncated file)");
  }
  std::memcpy(out, source->data + source->offset, n);
  source->offset += n;
}

void pngError(png_structp png, png_const_charp what)
{
  copyMessage(static_cast<char *>(png_get_error_ptr(png)), what);
  png_longjmp(png, 1);
}

void pngWarning(png_structp, png_const_charp) {}

/*!
  Grey PNG decoding with OpenCV's transformations for a grey destination, in its order: 16-bit samples stripped to
  8 (or byte-swapped when kept), alpha stripped, palette expanded, 1/2/4-bit grey expanded, colour to grey with
  weights (0.299, 0.587). Exactly one of \e out8 and \e out16 is set.
*/
bool decodePng(const unsigned char *data, std::size_t size, vpImage<unsigned char> *out8,
               std::vector<std::uint16_t> *out16, unsigned int &width, unsigned int &height, int &fileDepth,
               char *message)
{
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, message, pngError, pngWarning);
  if (png == nullptr) {
    copyMessage(message, "cannot create a PNG reader");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    copyMessage(message, "cannot create a PNG reader");
    return false;
  }
  PngSource source{data, size, 0};
  // Everything with a destructor is constructed before setjmp: a longjmp must not skip one.
  std::vector<png_bytep> rows;
  vpImage<unsigned char> tmp;
  std::vector<unsigned char> rgb;
  if (setjmp(png_jmpbuf(png)) != 0) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_set_read_fn(png, &source, pngRead);
  png_read_info(png, info);
  png_uint_32 w = 0, h = 0;
  int depth = 0, colorType = 0;
  png_get_IHDR(png, info, &w, &h, &depth, &colorType, nullptr, nullptr, nullptr);
  if (!imageSizeAccepted(w, h)) {
    png_error(png, "bad image size in the PNG header");
  }
  const bool keep16 = out16 != nullptr && depth == 16;
  if (depth == 16 && !keep16) {
    png_set_strip_16(png);
  } else {
    png_set_swap(png); // little-endian samples when 16 bits are kept (x86-64, aarch64)
  }
  png_set_strip_alpha(png);
  if (colorType == PNG_COLOR_TYPE_PALETTE) {
    png_set_palette_to_rgb(png);
  }
  if ((colorType & PNG_COLOR_MASK_COLOR) == 0 && depth < 8) {
    png_set_expand_gray_1_2_4_to_8(png);
  }
  // 8-bit colour: RGB rows converted by ViSP's vpImageConvert::RGBToGrey, as vpImageIo::read did for PNG files.
  const bool viSPGrey = !keep16 && (colorType & PNG_COLOR_MASK_COLOR) != 0;
  if (!viSPGrey) {
    png_set_rgb_to_gray(png, 1, 0.299, 0.587);
  }
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  width = w;
  height = h;
  fileDepth = depth == 16 ? 16 : 8;
  rows.resize(h);
  if (keep16) {
    out16->resize(static_cast<std::size_t>(w) * h);
    for (png_uint_32 y = 0; y < h; ++y) {
      rows[y] = reinterpret_cast<png_bytep>(out16->data() + static_cast<std::size_t>(y) * w);
    }
    png_read_image(png, rows.data());
  } else {
    vpImage<unsigned char> &I = out8 != nullptr ? *out8 : tmp;
    I.resize(h, w);
    if (viSPGrey) {
      if (png_get_channels(png, info) != 3) {
        png_error(png, "unexpected PNG colour layout");
      }
      rgb.resize(static_cast<std::size_t>(w) * h * 3);
      for (png_uint_32 y = 0; y < h; ++y) {
        rows[y] = rgb.data() + static_cast<std::size_t>(y) * w * 3;
      }
      png_read_image(png, rows.data());
      vpImageConvert::RGBToGrey(rgb.data(), I.bitmap, static_cast<unsigned int>(w) * h);
    } else {
      for (png_uint_32 y = 0; y < h; ++y) {
        rows[y] = I[y];
      }
      png_read_image(png, rows.data());
    }
    if (out16 != nullptr) {
      out16->assign(I.bitmap, I.bitmap + I.getSize());
    }
  }
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

// ---- PGM / PPM (Netpbm), binary (P5, P6) and plain (P2, P3).

struct PnmReader {
  const unsigned char *data;
  std::size_t size;
  std::size_t pos;

  void skipSpaceAndComments()
  {
    while (pos < size) {
      if (data[pos] == '#') {
        while (pos < size && data[pos] != '\n') {
          ++pos;
        }
      } else if (std::isspace(data[pos])) {
        ++pos;
      } else {
        return;
      }
    }
  }
  //! A decimal header or plain-format value; false when none.
  bool number(unsigned long &value)
  {
    skipSpaceAndComments();
    if (pos >= size || !std::isdigit(data[pos])) {
      return false;
    }
    value = 0;
    while (pos < size && std::isdigit(data[pos])) {
      value = value * 10 + static_cast<unsigned long>(data[pos] - '0');
      if (value > 0xFFFFFFul) {
        return false;
      }
      ++pos;
    }
    return true;
  }
};

//! Samples as stored (0..maxval), grey or converted from colour with OpenCV's weights.
void decodePnm(const unsigned char *data, std::size_t size, const std::string &name,
               std::vector<std::uint16_t> &samples, unsigned int &width, unsigned int &height, int &fileDepth)
{
  const char kind = static_cast<char>(data[1]);
  const bool colour = kind == '3' || kind == '6';
  const bool plain = kind == '2' || kind == '3';
  PnmReader in{data, size, 2};
  unsigned long w = 0, h = 0, maxval = 0;
  if (!in.number(w) || !in.number(h) || !in.number(maxval)) {
    fail(name, "bad PGM/PPM header");
  }
  if (!imageSizeAccepted(w, h) || maxval == 0 || maxval > 65535) {
    fail(name, "bad PGM/PPM header (size or maximum value out of range)");
  }
  const int channels = colour ? 3 : 1;
  const int bytesPerSample = maxval > 255 ? 2 : 1;
  const std::size_t count = static_cast<std::size_t>(w) * h * static_cast<std::size_t>(channels);
  // The data must be able to hold the samples before they are allocated: a plain sample takes at least a digit and a
  // separator (the last one no separator), a binary one its bytes after the single whitespace that ends the header.
  const std::size_t left = in.pos < size ? size - in.pos : 0;
  const bool fits =
      plain ? count <= (left + 1) / 2 : left > 0 && (left - 1) / static_cast<std::size_t>(bytesPerSample) >= count;
  if (!fits) {
    fail(name, "the PGM/PPM data ends early (truncated file, or a header whose size is wrong)");
  }
  std::vector<std::uint16_t> raw(count);
  if (plain) {
    for (std::size_t i = 0; i < count; ++i) {
      unsigned long v = 0;
      if (!in.number(v) || v > maxval) {
        fail(name, "the PGM/PPM data ends early or holds a value above its maximum");
      }
      raw[i] = static_cast<std::uint16_t>(v);
    }
  } else {
    ++in.pos; // exactly one whitespace character after the maximum value (room checked above)
    const unsigned char *p = data + in.pos;
    for (std::size_t i = 0; i < count; ++i) {
      raw[i] = bytesPerSample == 1 ? p[i] : static_cast<std::uint16_t>((p[2 * i] << 8) | p[2 * i + 1]);
    }
  }
  width = static_cast<unsigned int>(w);
  height = static_cast<unsigned int>(h);
  fileDepth = bytesPerSample == 2 ? 16 : 8;
  if (!colour) {
    samples.swap(raw);
    return;
  }
  if (bytesPerSample == 1) {
    // 8-bit colour: ViSP's vpImageConvert::RGBToGrey, as vpImageIo::read did for PPM files.
    std::vector<unsigned char> rgb(raw.begin(), raw.end());
    std::vector<unsigned char> grey(static_cast<std::size_t>(w) * h);
    vpImageConvert::RGBToGrey(rgb.data(), grey.data(), static_cast<unsigned int>(w * h));
    samples.assign(grey.begin(), grey.end());
    return;
  }
  samples.resize(static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const std::uint64_t r = raw[3 * i], g = raw[3 * i + 1], b = raw[3 * i + 2];
    samples[i] = static_cast<std::uint16_t>(
        (r * kGreyWeightR + g * kGreyWeightG + b * kGreyWeightB + (1u << (kGreyShift - 1))) >> kGreyShift);
  }
}

void requireSignature(const unsigned char *data, std::size_t size, const std::string &name, ImageFormat &format)
{
  format = detectImageFormat(data, size);
  if (format == ImageFormat::unknown) {
    fail(name, size == 0 ? std::string("the file is empty")
                         : std::string("not a JPEG, PNG, PGM or PPM file (other formats: convert them, e.g. to PNG)"));
  }
}

//! libpng's writing calls; false when libpng reported an error (its message in the error pointer).
bool writePngData(png_structp png, png_infop info, std::FILE *file, unsigned int width, unsigned int height,
                  int channels, const std::vector<png_bytep> &rows)
{
  if (setjmp(png_jmpbuf(png)) != 0) {
    return false;
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, width, height, 8, channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_image(png, const_cast<png_bytepp>(rows.data()));
  png_write_end(png, nullptr);
  return true;
}

//! Write 8-bit rows of \e channels samples per pixel (1 grey, 3 RGB) as a PNG.
void writePngRows(const std::string &path, unsigned int width, unsigned int height, int channels,
                  const std::vector<png_bytep> &rows)
{
  std::FILE *file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot write the image '" + path + "'");
  }
  char message[kMessageSize] = "";
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, message, pngError, pngWarning);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  const bool written = info != nullptr && writePngData(png, info, file, width, height, channels, rows);
  png_destroy_write_struct(&png, &info);
  const bool closed = std::fclose(file) == 0;
  if (!written || !closed) {
    throw vpHSlamException(vpHSlamException::fileUnreadable,
                           "cannot write the image '" + path + "'" + (message[0] ? std::string(": ") + message : ""));
  }
}
} // namespace

ImageFormat detectImageFormat(const unsigned char *data, std::size_t size)
{
  static const unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF) {
    return ImageFormat::jpeg;
  }
  if (size >= sizeof(kPng) && std::memcmp(data, kPng, sizeof(kPng)) == 0) {
    return ImageFormat::png;
  }
  if (size >= 3 && data[0] == 'P' && (data[1] == '2' || data[1] == '3' || data[1] == '5' || data[1] == '6') &&
      std::isspace(data[2])) {
    return ImageFormat::pnm;
  }
  return ImageFormat::unknown;
}

std::vector<unsigned char> readFileBytes(const std::string &path)
{
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "cannot open '" + path + "'");
  }
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot read '" + path + "'");
  }
  return bytes;
}

void decodeGrey8(const unsigned char *data, std::size_t size, const std::string &name, vpImage<unsigned char> &I)
{
  ImageFormat format;
  requireSignature(data, size, name, format);
  char message[kMessageSize] = "";
  unsigned int w = 0, h = 0;
  int depth = 8;
  if (format == ImageFormat::jpeg) {
    if (!decodeJpeg(data, size, I, message)) {
      fail(name, message);
    }
    return;
  }
  if (format == ImageFormat::png) {
    if (!decodePng(data, size, &I, nullptr, w, h, depth, message)) {
      fail(name, message);
    }
    return;
  }
  std::vector<std::uint16_t> samples;
  decodePnm(data, size, name, samples, w, h, depth);
  I.resize(h, w);
  const int shift = depth == 16 ? 8 : 0; // 16-bit samples: high byte, as PNG files are reduced
  for (std::size_t i = 0; i < samples.size(); ++i) {
    I.bitmap[i] = static_cast<unsigned char>(samples[i] >> shift);
  }
}

void decodeGreyAnyDepth(const unsigned char *data, std::size_t size, const std::string &name,
                        std::vector<std::uint16_t> &samples, unsigned int &width, unsigned int &height, int &bitDepth)
{
  ImageFormat format;
  requireSignature(data, size, name, format);
  char message[kMessageSize] = "";
  if (format == ImageFormat::jpeg) {
    vpImage<unsigned char> I;
    if (!decodeJpeg(data, size, I, message)) {
      fail(name, message);
    }
    samples.assign(I.bitmap, I.bitmap + I.getSize());
    width = I.getWidth();
    height = I.getHeight();
    bitDepth = 8;
    return;
  }
  if (format == ImageFormat::png) {
    if (!decodePng(data, size, nullptr, &samples, width, height, bitDepth, message)) {
      fail(name, message);
    }
    return;
  }
  decodePnm(data, size, name, samples, width, height, bitDepth);
}

void writePng(const std::string &path, const vpImage<unsigned char> &I)
{
  std::vector<png_bytep> rows(I.getHeight());
  for (unsigned int y = 0; y < I.getHeight(); ++y) {
    rows[y] = const_cast<png_bytep>(I[y]);
  }
  writePngRows(path, I.getWidth(), I.getHeight(), 1, rows);
}

void writePng(const std::string &path, const vpImage<vpRGBa> &I)
{
  std::vector<unsigned char> rgb(static_cast<std::size_t>(I.getSize()) * 3);
  for (unsigned int i = 0; i < I.getSize(); ++i) {
    rgb[3 * i] = I.bitmap[i].R;
    rgb[3 * i + 1] = I.bitmap[i].G;
    rgb[3 * i + 2] = I.bitmap[i].B;
  }
  std::vector<png_bytep> rows(I.getHeight());
  for (unsigned int y = 0; y < I.getHeight(); ++y) {
    rows[y] = rgb.data() + static_cast<std::size_t>(y) * I.getWidth() * 3;
  }
  writePngRows(path, I.getWidth(), I.getHeight(), 3, rows);
}
} // namespace io
} // namespace hslam
