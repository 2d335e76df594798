/*
 * H-SLAM for ViSP.
 */
//! \file ImageCodec.h  The module's own still-image codec: JPEG (libjpeg), PNG (libpng), PGM and PPM.
#pragma once

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpRGBa.h>
#include <visp3/hslam/vpHSlamException.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hslam
{
namespace io
{
/*!
  Why the module decodes images itself instead of through ViSP's vpImageIo or OpenCV's imgcodecs: those two link
  OpenCV's image and video I/O, which on Debian pull in about 200 more shared libraries (GDAL, GStreamer, FFmpeg,
  Qt, ...). Loading and relocating them costs every program that links the module about 0.2 s of CPU at start-up and
  about 60 MB of resident memory, for formats a SLAM system does not read. The grey conversion is the one
  vpImageIo::read applied before (libjpeg's Y channel for JPEG, ViSP's vpImageConvert::RGBToGrey for 8-bit colour
  PNG and PPM), so a frame decodes to the same pixels as before; a unit test checks it against vpImageIo::read on
  every image of the shared sequences and on generated files. EXIF orientation tags are not applied (camera frames
  do not carry them).
*/

//! Encoded image formats recognised from their first bytes.
enum class ImageFormat { unknown, jpeg, png, pnm };

//! Format of an encoded image from its signature (JPEG FF D8, PNG 89 'PNG', PNM 'P2'/'P3'/'P5'/'P6').
VISP_EXPORT ImageFormat detectImageFormat(const unsigned char *data, std::size_t size);

//! The whole content of a file. \exception vpHSlamException::fileNotFound / fileUnreadable naming \e path.
VISP_EXPORT std::vector<unsigned char> readFileBytes(const std::string &path);

/*!
  Decode an encoded JPEG, PNG, PGM or PPM image to 8-bit grey: colour converted as vpImageIo::read does (libjpeg's
  Y channel for JPEG, vpImageConvert::RGBToGrey for 8-bit PNG and PPM), 16-bit samples reduced to their high byte,
  alpha dropped, palettes expanded.
  \exception vpHSlamException::fileUnreadable naming \e name when the data is not a complete image in one of these
  formats.
*/
VISP_EXPORT void decodeGrey8(const unsigned char *data, std::size_t size, const std::string &name,
                             vpImage<unsigned char> &I);

/*!
  Decode a grey (or colour, converted as decodeGrey8() does) image keeping 16-bit samples: \e samples holds
  width x height values, row by row, 0..255 for 8-bit files and 0..65535 for 16-bit PNG or PGM files.
  \param bitDepth : 8 or 16, the depth of the file.
*/
VISP_EXPORT void decodeGreyAnyDepth(const unsigned char *data, std::size_t size, const std::string &name,
                                    std::vector<std::uint16_t> &samples, unsigned int &width, unsigned int &height,
                                    int &bitDepth);

//! Write \e I as an 8-bit grey PNG. \exception vpHSlamException::fileUnreadable when the file cannot be written.
VISP_EXPORT void writePng(const std::string &path, const vpImage<unsigned char> &I);
//! Write \e I as an 8-bit RGB PNG (alpha dropped).
VISP_EXPORT void writePng(const std::string &path, const vpImage<vpRGBa> &I);
} // namespace io
} // namespace hslam
