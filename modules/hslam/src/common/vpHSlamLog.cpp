/*
 * H-SLAM for ViSP.
 */
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamLog.h>

#include <atomic>
#include <cctype>
#include <cstdio>
#include <memory>
#include <mutex>

namespace hslam
{
namespace
{
// Process-wide state. The sink is shared through a shared_ptr so that log() holds the mutex only to copy the
// pointer, and calls the sink outside the lock (a sink may log itself, or be slow, without blocking others).
struct LogState {
  std::atomic<int> level{static_cast<int>(vpHSlamLog::info)};
  std::atomic<bool> hasSink{false};
  std::mutex sinkMutex;
  std::shared_ptr<const vpHSlamLog::Sink> sink;
};

LogState &logState()
{
  // Function-local static: initialised on first use, so logging from other static initialisers is safe.
  static LogState state;
  return state;
}
} // namespace
} // namespace hslam

void vpHSlamLog::setLevel(Level level)
{
  hslam::logState().level.store(static_cast<int>(level));
}

vpHSlamLog::Level vpHSlamLog::getLevel()
{
  return static_cast<Level>(hslam::logState().level.load());
}

void vpHSlamLog::setSink(const Sink &sink)
{
  std::shared_ptr<const Sink> next = sink ? std::make_shared<const Sink>(sink) : nullptr;
  hslam::LogState &state = hslam::logState();
  {
    std::lock_guard<std::mutex> lock(state.sinkMutex);
    state.sink.swap(next);
    state.hasSink.store(static_cast<bool>(state.sink));
  }
  // The previous sink (now in `next`) is released here, outside the lock.
}

bool vpHSlamLog::hasSink()
{
  return hslam::logState().hasSink.load();
}

bool vpHSlamLog::isEnabled(Level level)
{
  const hslam::LogState &state = hslam::logState();
  return state.hasSink.load(std::memory_order_relaxed) &&
         static_cast<int>(level) <= state.level.load(std::memory_order_relaxed);
}

void vpHSlamLog::log(Level level, const std::string &message)
{
  if (!isEnabled(level)) {
    return;
  }
  hslam::LogState &state = hslam::logState();
  std::shared_ptr<const Sink> sink;
  {
    std::lock_guard<std::mutex> lock(state.sinkMutex);
    sink = state.sink;
  }
  if (!sink) {
    return; // removed between isEnabled() and the copy
  }
  try {
    (*sink)(level, message);
  } catch (...) {
    // Reporting must never change what the library computes: a failing sink loses the message, nothing more.
  }
}

vpHSlamLog::Sink vpHSlamLog::stderrSink()
{
  return [](Level level, const std::string &message) {
    // One complete line per fputs call: stdio locks the stream per call, so lines from threads do not interleave.
    const std::string line = std::string("[hslam] ") + levelName(level) + ": " + message + "\n";
    std::fputs(line.c_str(), stderr);
  };
}

const char *vpHSlamLog::levelName(Level level)
{
  switch (level) {
  case error:
    return "error";
  case warning:
    return "warning";
  case info:
    return "info";
  case debug:
    return "debug";
  }
  return "unknown";
}

vpHSlamLog::Level vpHSlamLog::levelFromString(const std::string &name)
{
  std::string lower;
  lower.reserve(name.size());
  for (char c : name) {
    lower.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  }
  const Level levels[] = {error, warning, info, debug};
  for (Level level : levels) {
    if (lower == levelName(level) || lower == std::to_string(static_cast<int>(level))) {
      return level;
    }
  }
  throw vpHSlamException(vpHSlamException::invalidArgument, "vpHSlamLog::levelFromString(): unknown log level '" +
                                                                name +
                                                                "' (expected error, warning, info, debug or 0-3)");
}
