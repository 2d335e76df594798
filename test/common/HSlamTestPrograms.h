// Test helpers for end-to-end tests: find a built tutorial program, run it capturing its output, and read the
// files it wrote (statistics JSON, TUM trajectories).
// Programs are found relative to the running test executable (<build>/test/ -> <build>/tutorials/).
#ifndef HSLAM_TEST_PROGRAMS_H
#define HSLAM_TEST_PROGRAMS_H

#include "HSlamTestData.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

namespace hslam_test
{
//! Path of the built tutorial program `name` (e.g. "tutorial-hslam-evaluate"), empty when it is not built.
inline std::string builtTutorialPath(const std::string &name)
{
  char self[4096];
  const ssize_t n = ::readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (n <= 0) {
    return std::string();
  }
  std::string dir(self, static_cast<size_t>(n));
  dir = dir.substr(0, dir.find_last_of('/'));
  const std::string path = dir + "/../tutorials/" + name;
  return pathExists(path) ? path : std::string();
}

//! Outcome of one program run.
struct ProgramRun {
  int exitCode = -1;  //!< exit status, -1 when the program could not start or did not exit normally
  std::string output; //!< stdout and stderr
};

//! Runs `program arguments` through the shell, stderr merged into the captured stdout.
inline ProgramRun runProgram(const std::string &program, const std::string &arguments)
{
  ProgramRun result;
  FILE *pipe = ::popen((program + " " + arguments + " 2>&1").c_str(), "r");
  if (!pipe) {
    return result;
  }
  char buffer[512];
  while (std::fgets(buffer, sizeof(buffer), pipe)) {
    result.output += buffer;
  }
  const int status = ::pclose(pipe);
  result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

//! Whole content of a text file, empty when it cannot be read.
inline std::string readTextFile(const std::string &path)
{
  std::ifstream in(path.c_str());
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

//! Value of "key": <number> in a flat JSON object (a statistics file), NaN when absent or not a number.
inline double jsonNumber(const std::string &json, const std::string &key)
{
  const std::string tag = "\"" + key + "\":";
  const std::size_t pos = json.find(tag);
  if (pos == std::string::npos) {
    return std::nan("");
  }
  const char *begin = json.c_str() + pos + tag.size();
  char *end = nullptr;
  const double x = std::strtod(begin, &end);
  return end == begin ? std::nan("") : x;
}

//! Value of "key": "<text>" in a flat JSON object (no escapes inside), "<absent>" when there is no such string.
inline std::string jsonString(const std::string &json, const std::string &key)
{
  const std::string tag = "\"" + key + "\": \"";
  const std::size_t pos = json.find(tag);
  const std::size_t end = pos == std::string::npos ? pos : json.find('"', pos + tag.size());
  return end == std::string::npos ? std::string("<absent>") : json.substr(pos + tag.size(), end - pos - tag.size());
}

//! Pose lines of a TUM trajectory file (comments and blank lines excluded).
inline std::size_t countTumPoses(const std::string &path)
{
  std::ifstream in(path.c_str());
  std::string line;
  std::size_t n = 0;
  while (std::getline(in, line)) {
    n += (!line.empty() && line[0] != '#') ? 1 : 0;
  }
  return n;
}
} // namespace hslam_test

#endif
