/*
 * H-SLAM for ViSP.
 */
//! \file SourceFiles.h  Shared helpers of the dataset readers: paths, folder listing, image reading. Text lists are
//! read with common/TextParsing.h.
#ifndef HSLAM_IO_SOURCE_FILES_H
#define HSLAM_IO_SOURCE_FILES_H

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

//! True for the still-image extensions the readers accept (png, jpg, jpeg, pgm, ppm, bmp, tif, tiff).
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
  Read one image as 8-bit grey (ViSP's readers convert colour files).
  \exception vpHSlamException::fileNotFound when missing, fileUnreadable when it cannot be decoded or is empty,
  both naming \e path.
*/
VISP_EXPORT void readGreyImage(const std::string &path, vpImage<unsigned char> &I);
} // namespace io
} // namespace hslam

#endif
