/*
 * H-SLAM for ViSP.
 */
//! \file SourceFiles.h  Shared helpers of the dataset readers: paths, folder listing, image reading. Text lists are
//! read with common/TextParsing.h.
#ifndef HSLAM_IO_SOURCE_FILES_H
#define HSLAM_IO_SOURCE_FILES_H

#include "common/TextParsing.h"

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>

#include <string>
#include <vector>

namespace hslam
{
//! Helpers of the image-source readers.
namespace io
{
//! a + "/" + b, without doubling the separator; b returned as is when absolute.
std::string joinPath(const std::string &a, const std::string &b);
//! Last path component, trailing separators ignored.
std::string baseName(const std::string &path);
//! Parent folder of a path ("." when there is none), trailing separators ignored.
std::string parentPath(const std::string &path);
//! File name without its last extension.
std::string stemName(const std::string &name);
//! Extension of a file name in lower case, without the dot ("" when none).
std::string lowerExtension(const std::string &name);

bool pathIsDirectory(const std::string &path);
bool pathIsFile(const std::string &path);

//! True for the still-image extensions the readers list (png, jpg, jpeg, pgm, ppm, bmp, tif, tiff). The module
//! decodes JPEG, PNG, PGM and PPM (io/ImageCodec.h); a BMP or TIFF frame gives an error that says to convert it.
VISP_EXPORT bool hasImageExtension(const std::string &name);
//! True for the video-file extensions handed to vpVideoReader (avi, mp4, mov, mkv, mpg, ...).
VISP_EXPORT bool hasVideoExtension(const std::string &name);

/*!
  Names (not paths) of the image files directly inside \e folder, sorted by name (byte order: zero-padded
  numbered files sort in sequence order).
  \exception vpHSlamException::fileNotFound when \e folder is not a directory.
*/
VISP_EXPORT std::vector<std::string> listImageFiles(const std::string &folder);

/*!
  Read one image (JPEG, PNG, PGM or PPM) as 8-bit grey, colour files converted as vpImageIo::read does.
  \exception vpHSlamException::fileNotFound when missing, fileUnreadable when it cannot be decoded, is empty, or is
  a JPEG cut before its end-of-image marker (which libjpeg would decode without error), all naming \e path.
*/
VISP_EXPORT void readGreyImage(const std::string &path, vpImage<unsigned char> &I);

/*!
  Decode an encoded image held in memory (JPEG, PNG, PGM or PPM, as read from an archive) to 8-bit grey.
  \param bytes : the encoded file.
  \param name : what to call it in messages ("images.zip:00012.png").
  \exception vpHSlamException::fileUnreadable naming \e name when it cannot be decoded or is a truncated JPEG.
*/
void decodeGreyImage(const std::vector<unsigned char> &bytes, const std::string &name, vpImage<unsigned char> &I);

/*!
  The data lines of an image or time list (readDataLines()), refusing a list whose last data line has no end of
  line: that is how a list cut during a copy or download ends, and a line cut inside its last number still parses
  (a timestamp "1.2345e+01" cut to "1.23"), so the cut must be caught here rather than by the line's content.
  \exception as readDataLines(); vpHSlamException::parseError naming the file and the line for an unterminated
  last data line.
*/
std::vector<TextLine> readListLines(const std::string &path, const std::string &what);
} // namespace io
} // namespace hslam

#endif
