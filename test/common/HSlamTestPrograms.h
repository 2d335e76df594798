// Test helpers for end-to-end tests: find a built tutorial program and run it, capturing its output.
// Programs are found relative to the running test executable (<build>/test/ -> <build>/tutorials/).
#ifndef HSLAM_TEST_PROGRAMS_H
#define HSLAM_TEST_PROGRAMS_H

#include "HSlamTestData.h"

#include <cstdio>
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
} // namespace hslam_test

#endif
