/*
 * H-SLAM for ViSP.
 */
#include "io/ZipArchive.h"

#include "io/SourceFiles.h"

#include <visp3/hslam/vpHSlamException.h>

#include <zip.h>

namespace hslam
{
namespace io
{
namespace
{
//! Largest entry read: far above any dataset image, low enough that a damaged size field cannot exhaust memory.
constexpr zip_uint64_t kMaxEntryBytes = 512ULL * 1024ULL * 1024ULL;

std::string libzipMessage(int code)
{
  zip_error_t error;
  zip_error_init_with_code(&error, code);
  const std::string text = zip_error_strerror(&error);
  zip_error_fini(&error);
  return text;
}

//! Closes a zip_file_t on every path out of ZipArchive::read().
class ScopedZipFile
{
public:
  explicit ScopedZipFile(zip_file_t *file) : m_file(file) {}
  ~ScopedZipFile()
  {
    if (m_file) {
      zip_fclose(m_file);
    }
  }
  ScopedZipFile(const ScopedZipFile &) = delete;
  ScopedZipFile &operator=(const ScopedZipFile &) = delete;
  zip_file_t *get() const { return m_file; }

private:
  zip_file_t *m_file;
};
} // namespace

ZipArchive::ZipArchive(const std::string &path) : m_path(path)
{
  if (!pathIsFile(path)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "zip archive '" + path + "' does not exist");
  }
  int code = 0;
  // ZIP_CHECKCONS: compare the central directory with the local headers, so a damaged archive fails here.
  m_archive = zip_open(path.c_str(), ZIP_RDONLY | ZIP_CHECKCONS, &code);
  if (!m_archive) {
    throw vpHSlamException(vpHSlamException::fileUnreadable,
                           "cannot open zip archive '" + path + "': " + libzipMessage(code));
  }
}

ZipArchive::~ZipArchive()
{
  // Read-only: discard, nothing to write back.
  zip_discard(m_archive);
}

std::vector<std::string> ZipArchive::fileNames() const
{
  const zip_int64_t count = zip_get_num_entries(m_archive, 0);
  std::vector<std::string> names;
  for (zip_int64_t index = 0; index < count; ++index) {
    const char *name = zip_get_name(m_archive, static_cast<zip_uint64_t>(index), ZIP_FL_ENC_GUESS);
    if (!name) {
      throw vpHSlamException(vpHSlamException::fileUnreadable, "zip archive '" + m_path + "': entry " +
                                                                   std::to_string(index) +
                                                                   " has no readable name: " + zip_strerror(m_archive));
    }
    const std::string text(name);
    if (!text.empty() && text.back() != '/') {
      names.push_back(text);
    }
  }
  return names;
}

void ZipArchive::read(const std::string &name, std::vector<unsigned char> &bytes) const
{
  const std::string where = m_path + ":" + name;
  const zip_int64_t index = zip_name_locate(m_archive, name.c_str(), 0);
  if (index < 0) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "'" + where + "': no such entry in the archive");
  }
  zip_stat_t status;
  zip_stat_init(&status);
  if (zip_stat_index(m_archive, static_cast<zip_uint64_t>(index), 0, &status) != 0 || !(status.valid & ZIP_STAT_SIZE)) {
    throw vpHSlamException(vpHSlamException::fileUnreadable,
                           "'" + where + "': cannot read the entry's size: " + zip_strerror(m_archive));
  }
  if (status.size > kMaxEntryBytes) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "'" + where + "': entry of " +
                                                                 std::to_string(status.size) +
                                                                 " bytes, larger than any image: damaged archive?");
  }
  ScopedZipFile file(zip_fopen_index(m_archive, static_cast<zip_uint64_t>(index), 0));
  if (!file.get()) {
    throw vpHSlamException(vpHSlamException::fileUnreadable,
                           "'" + where + "': cannot open the entry: " + zip_strerror(m_archive));
  }
  bytes.resize(static_cast<std::size_t>(status.size));
  zip_uint64_t done = 0;
  while (done < status.size) {
    const zip_int64_t n = zip_fread(file.get(), bytes.data() + done, status.size - done);
    if (n <= 0) {
      throw vpHSlamException(
          vpHSlamException::fileUnreadable,
          "'" + where + "': " +
              (n < 0
                   ? std::string("cannot decompress the entry: ") + zip_error_strerror(zip_file_get_error(file.get()))
                   : "entry ends after " + std::to_string(done) + " of its " + std::to_string(status.size) + " bytes"));
    }
    done += static_cast<zip_uint64_t>(n);
  }
  // libzip checks the CRC when the stream reaches its end: read once more to get there.
  unsigned char extra = 0;
  const zip_int64_t tail = zip_fread(file.get(), &extra, 1);
  if (tail != 0) {
    throw vpHSlamException(
        vpHSlamException::fileUnreadable,
        "'" + where + "': " +
            (tail < 0 ? std::string("damaged entry: ") + zip_error_strerror(zip_file_get_error(file.get()))
                      : std::string("entry is longer than its recorded size")));
  }
}
} // namespace io
} // namespace hslam
