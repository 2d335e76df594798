/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamImageIo.h
  \brief Reading and writing still images without OpenCV's image I/O (JPEG, PNG, PGM, PPM).
*/
#ifndef VP_HSLAM_IMAGE_IO_H
#define VP_HSLAM_IMAGE_IO_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpRGBa.h>

#include <string>

/*!
  \class vpHSlamImageIo
  \ingroup group_hslam
  \brief The image files the module and its programs read and write, with libjpeg and libpng directly.

  What it is for: vpImageIo (ViSP's io module) links OpenCV's image and video I/O, and on Debian those pull in about
  200 shared libraries (GDAL, FFmpeg, GStreamer, Qt, ...). A program that links them spends ~0.2 s of CPU loading
  them at every start and holds ~60 MB more memory, for formats a SLAM system does not use. The module's dataset
  readers decode frames through this class instead, and the tutorials save their pictures with it, so they do not
  link ViSP's io module at all. A program that already uses vpImageIo can keep doing so: the results are the same.

  Reading: JPEG, PNG (8 or 16 bits, grey, colour, palette, alpha), PGM and PPM (binary or plain), converted to 8-bit
  grey exactly as vpImageIo::read does (libjpeg's Y channel for JPEG, vpImageConvert::RGBToGrey for colour PNG and
  PPM, 16-bit samples reduced to their high byte). Other formats (BMP, TIFF, ...) give an error that says to convert
  them.
  Writing: PNG only, 8-bit grey or RGB.

  Errors throw vpHSlamException (fileNotFound, fileUnreadable) naming the file. All functions are thread-safe.

  \code
  vpImage<unsigned char> I;
  vpHSlamImageIo::readGrey("frame.jpg", I);
  vpHSlamImageIo::writePng("frame.png", I);
  \endcode
*/
class VISP_EXPORT vpHSlamImageIo
{
public:
  //! Read a JPEG, PNG, PGM or PPM file as 8-bit grey.
  static void readGrey(const std::string &path, vpImage<unsigned char> &I);
  //! Write \e I as an 8-bit grey PNG file.
  static void writePng(const std::string &path, const vpImage<unsigned char> &I);
  //! Write \e I as an 8-bit RGB PNG file (alpha dropped).
  static void writePng(const std::string &path, const vpImage<vpRGBa> &I);
};

#endif
