// Support of the fuzz targets (test/fuzz/fuzz_*.cpp): the parsers read files, so each input is written to a file
// in a scratch folder of this process (removed at exit) before the parser under test reads it.
#ifndef HSLAM_FUZZ_INPUT_H
#define HSLAM_FUZZ_INPUT_H

#include <visp3/core/vpIoTools.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <signal.h>
#include <string>
#include <system_error>
#include <unistd.h>

namespace hslam_fuzz
{
//! Scratch folder of this process, removed at exit: /dev/shm/hslam-fuzz-<pid> when /dev/shm exists (in memory,
//! many times more inputs per second than on a disk), else $TMPDIR or /tmp. Held by a pointer that is never freed, so
//! that the exit handler never sees a destroyed string.
inline const std::string &scratchDir()
{
  static const std::string *const dir = []() {
    const char *tmp = std::getenv("TMPDIR");
    const std::string base = vpIoTools::checkDirectory("/dev/shm") ? std::string("/dev/shm")
                             : (tmp && *tmp)                       ? std::string(tmp)
                                                                   : std::string("/tmp");
    // libFuzzer ends some runs with _Exit (no exit handlers): remove what such runs left, when their process is gone.
    std::error_code error;
    for (const auto &entry : std::filesystem::directory_iterator(base, error)) {
      const std::string name = entry.path().filename().string();
      if (name.compare(0, 11, "hslam-fuzz-") == 0) {
        const long pid = std::strtol(name.c_str() + 11, nullptr, 10);
        if (pid > 0 && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
          std::filesystem::remove_all(entry.path(), error);
        }
      }
    }
    const std::string *path = new std::string(base + "/hslam-fuzz-" + std::to_string(static_cast<long>(::getpid())));
    vpIoTools::makeDirectory(*path);
    std::atexit([]() { vpIoTools::remove(scratchDir()); });
    return path;
  }();
  return *dir;
}

//! Writes \e size bytes to \e relative (inside the scratch folder; its folders must exist) and returns the path.
inline std::string writeFile(const std::string &relative, const uint8_t *data, std::size_t size)
{
  const std::string path = scratchDir() + "/" + relative;
  FILE *f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) {
    std::abort(); // the harness itself is broken: not a finding
  }
  if (size > 0 && std::fwrite(data, 1, size, f) != size) {
    std::abort();
  }
  std::fclose(f);
  return path;
}

//! Writes a text file (fixed content the harness needs beside the input).
inline std::string writeText(const std::string &relative, const std::string &text)
{
  return writeFile(relative, reinterpret_cast<const uint8_t *>(text.data()), text.size());
}

//! Creates \e relative (and its parents) inside the scratch folder; returns the path.
inline std::string makeDir(const std::string &relative)
{
  const std::string path = scratchDir() + "/" + relative;
  vpIoTools::makeDirectory(path);
  return path;
}
} // namespace hslam_fuzz

#endif
