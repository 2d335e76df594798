/*
 * H-SLAM for ViSP.
 */
//! \file ZipArchive.h  Read-only access to the entries of a zip archive (TUM monoVO images.zip), through libzip.
#ifndef HSLAM_IO_ZIP_ARCHIVE_H
#define HSLAM_IO_ZIP_ARCHIVE_H

#include <cstddef>
#include <string>
#include <vector>

struct zip;

namespace hslam
{
namespace io
{
/*!
  A zip archive opened for reading, entries addressed by their name. Used to read TUM monoVO's images.zip in
  place, without unpacking it.

  The archive is opened once (with libzip's consistency check, so a truncated or damaged central directory fails
  at open) and stays open for the object's lifetime; entries are decompressed on demand, whole, and their CRC is
  verified. Errors are vpHSlamException naming the archive, and the entry as "<archive>:<entry>".

  Threading and ownership: owns the libzip handle; not copyable; one thread at a time (libzip handles are not
  thread-safe).
*/
class ZipArchive
{
public:
  /*!
    \exception vpHSlamException::fileNotFound when \e path does not exist, fileUnreadable when it is not a zip
    archive or its directory is damaged.
  */
  explicit ZipArchive(const std::string &path);
  ~ZipArchive();
  ZipArchive(const ZipArchive &) = delete;
  ZipArchive &operator=(const ZipArchive &) = delete;

  const std::string &path() const { return m_path; }

  //! Names of the file entries in archive order (folder entries, whose name ends with '/', left out).
  std::vector<std::string> fileNames() const;

  /*!
    Decompress entry \e name whole into \e bytes (resized; its capacity is reused from call to call).
    \exception vpHSlamException::fileNotFound when the archive has no such entry, fileUnreadable when it cannot be
    decompressed or fails its CRC check, naming "<archive>:<name>".
  */
  void read(const std::string &name, std::vector<unsigned char> &bytes) const;

private:
  std::string m_path;
  struct zip *m_archive = nullptr;
};
} // namespace io
} // namespace hslam

#endif
