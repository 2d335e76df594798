/*
 * H-SLAM for ViSP.
 */
//! \file TumMonoSource.h  TUM monoVO sequence reader.
#ifndef HSLAM_IO_TUM_MONO_SOURCE_H
#define HSLAM_IO_TUM_MONO_SOURCE_H

#include "io/IndexedImageSource.h"
#include "io/ZipArchive.h"

#include <memory>
#include <string>
#include <vector>

namespace hslam
{
/*!
  TUM monoVO reader (Engel et al. 2016 layout): the images, `times.txt` ("id time[s] [exposure[ms]]" per line,
  one per image, same order, the same number of columns on every line), `camera.txt` (DSO format, or
  Options::cameraFile), and the optional photometric calibration `pcalib.txt` + `vignette.png`.

  The images are the folder `images/` (image files sorted by name) or, when there is no such folder, the archive
  `images.zip` read in place: its image entries (folders and non-image names left out) sorted by name, as the
  benchmark's own reader does, each decompressed and decoded from memory when acquire() reaches it. A corrupt
  entry raises vpHSlamException::fileUnreadable naming "images.zip:<entry>".

  A different count of images and times.txt lines, or an id that disagrees with the numbered image name, raises
  vpHSlamException::invalidTimestamps naming times.txt.
*/
class TumMonoSource : public IndexedImageSource
{
public:
  TumMonoSource(const std::string &path, const vpHSlamImageSource::Options &options);

protected:
  void readArchivedImage(const IndexedFrame &frame, vpImage<unsigned char> &I) override;

private:
  std::unique_ptr<io::ZipArchive> m_archive; //!< images.zip when the images are read from it, else null
  std::vector<unsigned char> m_encoded;      //!< last entry read, reused from frame to frame
};
} // namespace hslam

#endif
