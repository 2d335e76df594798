/*
 * H-SLAM for ViSP.
 */
//! \file SourceFiles.h  Shared helpers of the dataset readers: paths, listing, text lines, strict number parsing.
#ifndef HSLAM_IO_SOURCE_FILES_H
#define HSLAM_IO_SOURCE_FILES_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>

#include <cstdint>
#include <string>
#include <vector>

namespace hslam
{
//! Helpers of the image-source readers (kept apart from camera/TextParsing.h's names).
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

//! One meaningful line of a text file, with its 1-based number for error messages.
struct TextLine {
  unsigned int number = 0;
  std::string text; //!< trimmed, never empty, never a comment
};

/*!
  Read a text list (rgb.txt, times.txt, data.csv, ...): blank lines and lines whose first non-blank character is
  \e comment are skipped; '\\r' of Windows line ends is removed.
  \exception vpHSlamException::fileNotFound or fileUnreadable naming \e path.
*/
VISP_EXPORT std::vector<TextLine> readTextLines(const std::string &path, char comment = '#');

//! Split on any character of \e separators, dropping empty fields (so "a  b" gives two fields).
VISP_EXPORT std::vector<std::string> splitFields(const std::string &text, const std::string &separators);

//! "file:line" for messages.
std::string fileLine(const std::string &path, unsigned int line);

/*!
  Strict parsing: the whole field must be a finite number.
  \exception vpHSlamException::parseError naming \e path, \e line and \e what.
*/
VISP_EXPORT double parseDouble(const std::string &field, const std::string &path, unsigned int line,
                               const std::string &what);
//! Strict parsing of a non-negative integer (e.g. EuRoC nanoseconds). \exception as parseDouble().
VISP_EXPORT std::uint64_t parseUnsigned(const std::string &field, const std::string &path, unsigned int line,
                                        const std::string &what);

/*!
  Read one image as 8-bit grey (ViSP's readers convert colour files).
  \exception vpHSlamException::fileNotFound when missing, fileUnreadable when it cannot be decoded or is empty,
  both naming \e path.
*/
VISP_EXPORT void readGreyImage(const std::string &path, vpImage<unsigned char> &I);
} // namespace io
} // namespace hslam

#endif
