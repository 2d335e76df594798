/*
 * H-SLAM for ViSP.
 */
#include <visp3/hslam/vpHSlamImageIo.h>

#include "io/ImageCodec.h"
#include "io/SourceFiles.h"

void vpHSlamImageIo::readGrey(const std::string &path, vpImage<unsigned char> &I)
{
  hslam::io::readGreyImage(path, I);
}

namespace
{
//! PNG data under another extension would mislead every viewer: the name must say PNG.
void requirePngName(const std::string &path)
{
  if (hslam::io::lowerExtension(path) != "png") {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "cannot write the image '" + path + "': only PNG files are written, name it *.png");
  }
}
} // namespace

void vpHSlamImageIo::writePng(const std::string &path, const vpImage<unsigned char> &I)
{
  requirePngName(path);
  hslam::io::writePng(path, I);
}

void vpHSlamImageIo::writePng(const std::string &path, const vpImage<vpRGBa> &I)
{
  requirePngName(path);
  hslam::io::writePng(path, I);
}
