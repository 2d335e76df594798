/*
 * H-SLAM for ViSP.
 */
#include "common/BinaryIo.h"

#include "common/TextParsing.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cstring>
#include <filesystem>
#include <fstream>

namespace hslam
{
void ByteWriter::u32(std::uint32_t v)
{
  for (int b = 0; b < 4; ++b) {
    m_bytes.push_back(static_cast<char>((v >> (8 * b)) & 0xff));
  }
}

void ByteWriter::u64(std::uint64_t v)
{
  for (int b = 0; b < 8; ++b) {
    m_bytes.push_back(static_cast<char>((v >> (8 * b)) & 0xff));
  }
}

void ByteWriter::f32(float v)
{
  std::uint32_t bits = 0;
  std::memcpy(&bits, &v, sizeof(bits));
  u32(bits);
}

void ByteWriter::f64(double v)
{
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof(bits));
  u64(bits);
}

const unsigned char *ByteReader::take(std::size_t size, const char *what)
{
  if (size > remaining()) {
    throwAt(vpHSlamException::parseError, m_path, 0,
            std::string("truncated: the file ends inside ") + what + " (offset " + std::to_string(m_offset) + ")");
  }
  const auto *p = reinterpret_cast<const unsigned char *>(m_bytes.data()) + m_offset;
  m_offset += size;
  return p;
}

std::uint8_t ByteReader::u8(const char *what)
{
  return *take(1, what);
}

std::uint32_t ByteReader::u32(const char *what)
{
  return loadU32(take(4, what));
}

std::uint64_t ByteReader::u64(const char *what)
{
  return loadU64(take(8, what));
}

float ByteReader::f32(const char *what)
{
  const std::uint32_t bits = u32(what);
  float v = 0.f;
  std::memcpy(&v, &bits, sizeof(v));
  return v;
}

double ByteReader::f64(const char *what)
{
  const std::uint64_t bits = u64(what);
  double v = 0.;
  std::memcpy(&v, &bits, sizeof(v));
  return v;
}

void ByteReader::raw(void *out, std::size_t size, const char *what)
{
  std::memcpy(out, take(size, what), size);
}

void ByteReader::requireRecords(std::uint64_t count, std::size_t recordBytes, const char *what) const
{
  if (recordBytes > 0 && count > remaining() / recordBytes) {
    throwAt(vpHSlamException::parseError, m_path, 0,
            "truncated or corrupt: " + std::to_string(count) + " " + what + " announced, only " +
                std::to_string(remaining()) + " bytes left");
  }
}

std::string readBinaryFile(const std::string &path, const std::string &what)
{
  requireFileExists(path, what);
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throwAt(vpHSlamException::fileUnreadable, path, 0, "is a folder, not a " + what);
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throwAt(vpHSlamException::fileUnreadable, path, 0, "cannot open the " + what);
  }
  // One read of the known size: several times faster than stream iterators on a 50 MB file.
  std::string bytes;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec) {
    bytes.resize(static_cast<std::size_t>(size));
    in.read(&bytes[0], static_cast<std::streamsize>(size));
    bytes.resize(static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad() || ec) {
    throwAt(vpHSlamException::fileUnreadable, path, 0, "read error");
  }
  if (bytes.empty()) {
    throwAt(vpHSlamException::parseError, path, 0, "empty " + what);
  }
  return bytes;
}

void writeFileAtomically(const std::string &path, const std::string &bytes, const std::string &what)
{
  const std::string temporary = path + ".partial";
  std::ofstream out;
  openForWriting(out, temporary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  flushAndClose(out, temporary);
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    throwAt(vpHSlamException::fileUnreadable, path, 0, "cannot write the " + what + " (rename failed)");
  }
}
} // namespace hslam
