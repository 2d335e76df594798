/*
 * H-SLAM for ViSP.
 */
/*!
  \file BinaryIo.h
  \brief Little-endian binary records for H-SLAM's own files (vocabulary, map): a writer appending to a byte string,
  a bounds-checked reader that reports a truncated file instead of reading past its end, whole-file read and an
  atomic write (temporary file renamed over the target, so an interrupted save never leaves half a file).

  Every multi-byte value is little-endian whatever the host; doubles and floats travel as their IEEE-754 bits, so a
  write and a read give back exactly the same numbers.
*/
#ifndef HSLAM_COMMON_BINARY_IO_H
#define HSLAM_COMMON_BINARY_IO_H

#include <visp3/core/vpConfig.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

namespace hslam
{
//! Little-endian record writer (appends to a byte string).
class VISP_EXPORT ByteWriter
{
public:
  void u8(std::uint8_t v) { m_bytes.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v);
  void u64(std::uint64_t v);
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void f32(float v);
  void f64(double v);
  void raw(const void *data, std::size_t size) { m_bytes.append(static_cast<const char *>(data), size); }

  const std::string &bytes() const { return m_bytes; }
  std::string &bytes() { return m_bytes; }

private:
  std::string m_bytes;
};

/*!
  Little-endian record reader over a byte buffer. Reading past the end throws vpHSlamException::parseError naming
  \e path and what was being read ("truncated ...").
*/
class VISP_EXPORT ByteReader
{
public:
  ByteReader(const std::string &bytes, const std::string &path) : m_bytes(bytes), m_path(path) {}

  std::uint8_t u8(const char *what);
  std::uint32_t u32(const char *what);
  std::uint64_t u64(const char *what);
  std::int32_t i32(const char *what) { return static_cast<std::int32_t>(u32(what)); }
  float f32(const char *what);
  double f64(const char *what);
  void raw(void *out, std::size_t size, const char *what);

  std::size_t offset() const { return m_offset; }
  std::size_t remaining() const { return m_bytes.size() - m_offset; }
  //! Throws when a count read from the file announces more records of \e recordBytes than bytes remain (a corrupt
  //! count must not reserve gigabytes before the read fails).
  void requireRecords(std::uint64_t count, std::size_t recordBytes, const char *what) const;

private:
  const unsigned char *take(std::size_t size, const char *what);

  const std::string &m_bytes;
  std::string m_path;
  std::size_t m_offset = 0;
};

//! Little-endian words of a byte buffer (no bounds check: the caller has checked the size). Inline, one load on a
//! little-endian host: the vocabulary reader calls them for every record, and the byte-by-byte assembly (which GCC
//! does not fuse into one load) made hashing the shipped vocabulary about 40 % slower.
template <typename Word> inline Word loadLittleEndian(const std::uint8_t *p)
{
  Word word = 0;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  std::memcpy(&word, p, sizeof(word));
#else
  for (std::size_t b = 0; b < sizeof(Word); ++b) {
    word |= static_cast<Word>(static_cast<Word>(p[b]) << (8 * b));
  }
#endif
  return word;
}
inline std::uint32_t loadU32(const std::uint8_t *p)
{
  return loadLittleEndian<std::uint32_t>(p);
}
inline std::uint64_t loadU64(const std::uint8_t *p)
{
  return loadLittleEndian<std::uint64_t>(p);
}

/*!
  The whole file as bytes. Errors: fileNotFound, fileUnreadable (a folder, unreadable), parseError (empty file);
  \e what names the file kind in the messages ("vocabulary file", "map file").
*/
VISP_EXPORT std::string readBinaryFile(const std::string &path, const std::string &what);

//! Write \e bytes to a temporary file beside \e path, then rename it over \e path (fileUnreadable on failure).
VISP_EXPORT void writeFileAtomically(const std::string &path, const std::string &bytes, const std::string &what);
} // namespace hslam

#endif
