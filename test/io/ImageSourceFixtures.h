// Fixtures of the image-source tests: temporary folders, small synthetic sequences in every layout, a stored-entry
// zip writer, and file-damaging helpers for the broken-copy tests. Everything is written under the system temp dir.
#ifndef HSLAM_TEST_IMAGE_SOURCE_FIXTURES_H
#define HSLAM_TEST_IMAGE_SOURCE_FIXTURES_H

#include <gtest/gtest.h>

#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/io/vpImageIo.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace hslam_test
{
//! A fresh folder under the system temp dir, removed with its content at scope exit.
struct TempDir {
  std::string path;
  TempDir()
  {
    std::string tmpl = (std::filesystem::temp_directory_path() / "hslam_sources_XXXXXX").string();
    std::vector<char> buf(tmpl.begin(), tmpl.end());
    buf.push_back('\0');
    const char *made = ::mkdtemp(buf.data());
    path = made ? std::string(made) : std::string();
  }
  ~TempDir()
  {
    std::error_code ec;
    if (!path.empty()) {
      std::filesystem::remove_all(path, ec);
    }
  }
  TempDir(const TempDir &) = delete;
  TempDir &operator=(const TempDir &) = delete;
  std::string operator/(const std::string &rel) const { return path + "/" + rel; }
};

inline void writeText(const std::string &path, const std::string &text)
{
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
}

inline std::vector<unsigned char> readBytes(const std::string &path)
{
  std::ifstream in(path, std::ios::binary);
  return std::vector<unsigned char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline void writeBytes(const std::string &path, const std::vector<unsigned char> &bytes)
{
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char *>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

inline void copyFile(const std::string &from, const std::string &to)
{
  std::filesystem::create_directories(std::filesystem::path(to).parent_path());
  std::filesystem::copy_file(from, to, std::filesystem::copy_options::overwrite_existing);
}

inline std::vector<std::string> readLines(const std::string &path)
{
  std::vector<std::string> lines;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    lines.push_back(line);
  }
  return lines;
}

//! Keep the first half of a file: a copy or download cut in the middle.
inline void truncateToHalf(const std::string &path)
{
  std::vector<unsigned char> bytes = readBytes(path);
  bytes.resize(bytes.size() / 2);
  writeBytes(path, bytes);
}

//! Cut the last line of a list file in its middle, leaving it without an end of line.
inline void cutLastLineMidway(const std::string &path)
{
  std::string text;
  {
    std::ifstream in(path, std::ios::binary);
    text.assign((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  while (!text.empty() && text.back() == '\n') {
    text.pop_back();
  }
  const std::size_t start = text.find_last_of('\n') + 1; // 0 when one line only
  writeText(path, text.substr(0, start + (text.size() - start) / 2));
}

//! Grey test pattern of frame \e i: different per frame, textured, exact in PNG.
inline vpImage<unsigned char> patternImage(unsigned int i, unsigned int width = 64, unsigned int height = 48)
{
  vpImage<unsigned char> I(height, width);
  for (unsigned int v = 0; v < height; ++v) {
    for (unsigned int u = 0; u < width; ++u) {
      I[v][u] = static_cast<unsigned char>((u * 3 + v * 2 + i * 10) % 256);
    }
  }
  return I;
}

//! DSO camera.txt of the 64x48 test images.
inline const char *testCameraText()
{
  return "Pinhole 50 50 31.5 23.5 0\n64 48\nnone\n64 48\n";
}

//! Reads every frame; returns their metadata and checks size and order on the way.
inline std::vector<vpHSlamImageSource::Frame> readAll(vpHSlamImageSource &source, unsigned int width,
                                                      unsigned int height)
{
  std::vector<vpHSlamImageSource::Frame> frames;
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  while (source.acquire(I, frame)) {
    EXPECT_EQ(I.getWidth(), width);
    EXPECT_EQ(I.getHeight(), height);
    EXPECT_EQ(frame.index, frames.size());
    frames.push_back(frame);
  }
  EXPECT_FALSE(source.acquire(I, frame)) << "acquire after the end must keep returning false";
  return frames;
}

//! Exposure of frame i in the synthetic TUM monoVO folder, milliseconds.
inline double tumMonoExposure(unsigned int i)
{
  return 5. + 2.5 * i;
}
//! Time of frame i in the synthetic TUM monoVO folder, seconds.
inline double tumMonoTime(unsigned int i)
{
  return 100. + 0.05 * i;
}

//! Synthetic TUM monoVO folder: \e n 64x48 PNGs (patternImage), times.txt with exposures, camera.txt, pcalib.txt.
inline std::string makeTumMono(const TempDir &tmp, unsigned int n)
{
  const std::string dir = tmp / "tum_mono";
  std::filesystem::create_directories(dir + "/images");
  std::ostringstream times;
  for (unsigned int i = 0; i < n; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "%05u.png", i);
    vpImageIo::write(patternImage(i), dir + "/images/" + name);
    times << std::string(name, 5) << " " << tumMonoTime(i) << " " << tumMonoExposure(i) << "\n";
  }
  writeText(dir + "/times.txt", times.str());
  writeText(dir + "/camera.txt", testCameraText());
  std::ostringstream pcalib;
  for (int k = 0; k < 256; ++k) {
    pcalib << 255. * std::pow(k / 255., 1.2) << (k < 255 ? " " : "\n");
  }
  writeText(dir + "/pcalib.txt", pcalib.str());
  return dir;
}

//! One file of a zip archive written by writeStoredZip().
struct ZipEntry {
  std::string name;
  std::vector<unsigned char> bytes;
};

//! CRC-32 of zip (ISO 3309 polynomial, reflected), bitwise: the test archives are a few kilobytes.
inline std::uint32_t zipCrc32(const std::vector<unsigned char> &bytes)
{
  std::uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char byte : bytes) {
    crc ^= byte;
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
  }
  return ~crc;
}

/*!
  Write a zip archive whose entries are stored (method 0, no compression), following PKWARE's APPNOTE 4.3: local
  headers with the data, then the central directory and its end record. Written by hand so that the tests need no
  zip tool nor a link to libzip, and so that the reader is checked against an independent writer.
*/
inline void writeStoredZip(const std::string &path, const std::vector<ZipEntry> &entries)
{
  std::vector<unsigned char> out, central;
  auto put16 = [](std::vector<unsigned char> &b, unsigned int v) {
    b.push_back(static_cast<unsigned char>(v & 0xFF));
    b.push_back(static_cast<unsigned char>((v >> 8) & 0xFF));
  };
  auto put32 = [&put16](std::vector<unsigned char> &b, std::uint32_t v) {
    put16(b, v & 0xFFFF);
    put16(b, v >> 16);
  };
  const unsigned int version = 20;   // 2.0: stored entries, folders
  const unsigned int dosDate = 0x21; // 1980-01-01
  for (const ZipEntry &e : entries) {
    const std::uint32_t offset = static_cast<std::uint32_t>(out.size());
    const std::uint32_t crc = zipCrc32(e.bytes);
    const std::uint32_t size = static_cast<std::uint32_t>(e.bytes.size());
    const unsigned int nameLength = static_cast<unsigned int>(e.name.size());
    put32(out, 0x04034b50u); // local file header
    put16(out, version);
    put16(out, 0); // flags
    put16(out, 0); // method: stored
    put16(out, 0); // time
    put16(out, dosDate);
    put32(out, crc);
    put32(out, size); // compressed
    put32(out, size); // uncompressed
    put16(out, nameLength);
    put16(out, 0); // extra field
    out.insert(out.end(), e.name.begin(), e.name.end());
    out.insert(out.end(), e.bytes.begin(), e.bytes.end());

    put32(central, 0x02014b50u); // central directory header
    put16(central, version);     // made by
    put16(central, version);     // needed
    put16(central, 0);
    put16(central, 0);
    put16(central, 0);
    put16(central, dosDate);
    put32(central, crc);
    put32(central, size);
    put32(central, size);
    put16(central, nameLength);
    put16(central, 0); // extra
    put16(central, 0); // comment
    put16(central, 0); // disk
    put16(central, 0); // internal attributes
    put32(central, 0); // external attributes
    put32(central, offset);
    central.insert(central.end(), e.name.begin(), e.name.end());
  }
  const std::uint32_t centralOffset = static_cast<std::uint32_t>(out.size());
  out.insert(out.end(), central.begin(), central.end());
  put32(out, 0x06054b50u); // end of central directory
  put16(out, 0);
  put16(out, 0);
  put16(out, static_cast<unsigned int>(entries.size()));
  put16(out, static_cast<unsigned int>(entries.size()));
  put32(out, static_cast<std::uint32_t>(central.size()));
  put32(out, centralOffset);
  put16(out, 0); // comment length
  writeBytes(path, out);
}

/*!
  Replace the images/ folder of a TUM monoVO folder by images.zip holding the same files, stored in REVERSED name
  order (the reader must sort); returns the entry names in sorted order.
*/
inline std::vector<std::string> zipTumMonoImages(const std::string &dir)
{
  std::vector<std::string> names;
  for (const auto &item : std::filesystem::directory_iterator(dir + "/images")) {
    names.push_back(item.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  std::vector<ZipEntry> entries;
  for (auto it = names.rbegin(); it != names.rend(); ++it) {
    entries.push_back({*it, readBytes(dir + "/images/" + *it)});
  }
  writeStoredZip(dir + "/images.zip", entries);
  std::filesystem::remove_all(dir + "/images");
  return names;
}
} // namespace hslam_test

#endif
