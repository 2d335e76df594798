// vpHSlamLog: silent by default, level filtering, the stderr sink, level parsing and concurrent logging.
#include "HSlamTestData.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamLog.h>

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

namespace
{
//! Collects messages; thread-safe because the log calls sinks outside its own lock.
struct Recorder {
  std::mutex mutex;
  std::vector<std::pair<vpHSlamLog::Level, std::string>> messages;

  vpHSlamLog::Sink sink()
  {
    return [this](vpHSlamLog::Level level, const std::string &message) {
      std::lock_guard<std::mutex> lock(mutex);
      messages.emplace_back(level, message);
    };
  }
};

const vpHSlamLog::Level kAllLevels[] = {vpHSlamLog::error, vpHSlamLog::warning, vpHSlamLog::info, vpHSlamLog::debug};

//! Restores the process-wide defaults after each test, so the order of tests does not matter.
class LogTest : public ::testing::Test
{
protected:
  void TearDown() override
  {
    vpHSlamLog::setSink(vpHSlamLog::Sink());
    vpHSlamLog::setLevel(vpHSlamLog::info);
  }
};
} // namespace

TEST_F(LogTest, DefaultIsSilent)
{
  EXPECT_FALSE(vpHSlamLog::hasSink());
  EXPECT_EQ(vpHSlamLog::getLevel(), vpHSlamLog::info);
  for (vpHSlamLog::Level level : kAllLevels) {
    EXPECT_FALSE(vpHSlamLog::isEnabled(level)) << vpHSlamLog::levelName(level);
  }
  testing::internal::CaptureStderr();
  testing::internal::CaptureStdout();
  vpHSlamLog::log(vpHSlamLog::error, "must not appear");
  bool evaluated = false;
  VP_HSLAM_LOG(vpHSlamLog::error, "lazy " << (evaluated = true));
  const std::string out = testing::internal::GetCapturedStdout();
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(out, "");
  EXPECT_EQ(err, "");
  EXPECT_FALSE(evaluated) << "the message was built although no sink is installed";
}

TEST_F(LogTest, SinkReceivesOnlyMessagesAtOrAboveLevel)
{
  Recorder recorder;
  vpHSlamLog::setSink(recorder.sink());
  EXPECT_TRUE(vpHSlamLog::hasSink());

  for (vpHSlamLog::Level threshold : kAllLevels) {
    recorder.messages.clear();
    vpHSlamLog::setLevel(threshold);
    EXPECT_EQ(vpHSlamLog::getLevel(), threshold);
    for (vpHSlamLog::Level level : kAllLevels) {
      EXPECT_EQ(vpHSlamLog::isEnabled(level), level <= threshold);
      vpHSlamLog::log(level, vpHSlamLog::levelName(level));
    }
    ASSERT_EQ(recorder.messages.size(), static_cast<std::size_t>(threshold) + 1)
        << "threshold " << vpHSlamLog::levelName(threshold);
    for (std::size_t i = 0; i < recorder.messages.size(); ++i) {
      EXPECT_EQ(recorder.messages[i].first, kAllLevels[i]);
      EXPECT_EQ(recorder.messages[i].second, vpHSlamLog::levelName(kAllLevels[i]));
    }
  }
}

TEST_F(LogTest, StreamMacroBuildsMessageOnlyWhenEnabled)
{
  Recorder recorder;
  vpHSlamLog::setSink(recorder.sink());
  vpHSlamLog::setLevel(vpHSlamLog::warning);
  int evaluations = 0;
  VP_HSLAM_LOG(vpHSlamLog::debug, "skipped " << ++evaluations);
  VP_HSLAM_LOG(vpHSlamLog::warning, "kept " << ++evaluations << " of " << 2.5);
  EXPECT_EQ(evaluations, 1);
  ASSERT_EQ(recorder.messages.size(), 1u);
  EXPECT_EQ(recorder.messages[0].first, vpHSlamLog::warning);
  EXPECT_EQ(recorder.messages[0].second, "kept 1 of 2.5");
}

TEST_F(LogTest, RemovingTheSinkSilencesAgain)
{
  Recorder recorder;
  vpHSlamLog::setSink(recorder.sink());
  vpHSlamLog::log(vpHSlamLog::error, "one");
  vpHSlamLog::setSink(nullptr);
  EXPECT_FALSE(vpHSlamLog::hasSink());
  EXPECT_FALSE(vpHSlamLog::isEnabled(vpHSlamLog::error));
  vpHSlamLog::log(vpHSlamLog::error, "two");
  ASSERT_EQ(recorder.messages.size(), 1u);
  EXPECT_EQ(recorder.messages[0].second, "one");
}

TEST_F(LogTest, StderrSinkWritesOneLinePerMessage)
{
  vpHSlamLog::setSink(vpHSlamLog::stderrSink());
  vpHSlamLog::setLevel(vpHSlamLog::warning);
  testing::internal::CaptureStderr();
  vpHSlamLog::log(vpHSlamLog::warning, "vignette missing");
  vpHSlamLog::log(vpHSlamLog::info, "filtered out");
  vpHSlamLog::log(vpHSlamLog::error, "lost");
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "[hslam] warning: vignette missing\n[hslam] error: lost\n");
}

TEST_F(LogTest, ThrowingSinkDoesNotPropagate)
{
  int calls = 0;
  vpHSlamLog::setSink([&calls](vpHSlamLog::Level, const std::string &) {
    ++calls;
    throw std::runtime_error("sink failure");
  });
  EXPECT_NO_THROW(vpHSlamLog::log(vpHSlamLog::error, "x"));
  EXPECT_EQ(calls, 1);
}

TEST_F(LogTest, LevelFromString)
{
  EXPECT_EQ(vpHSlamLog::levelFromString("error"), vpHSlamLog::error);
  EXPECT_EQ(vpHSlamLog::levelFromString("WARNING"), vpHSlamLog::warning);
  EXPECT_EQ(vpHSlamLog::levelFromString("Info"), vpHSlamLog::info);
  EXPECT_EQ(vpHSlamLog::levelFromString("3"), vpHSlamLog::debug);
  try {
    vpHSlamLog::levelFromString("verbose");
    ADD_FAILURE() << "no exception for an unknown level";
  } catch (const vpHSlamException &e) {
    EXPECT_EQ(e.getCode(), static_cast<int>(vpHSlamException::invalidArgument));
    EXPECT_NE(e.getStringMessage().find("'verbose'"), std::string::npos) << e.getStringMessage();
  }
}

TEST_F(LogTest, ConcurrentLoggingAndSinkSwapsLoseNothingDelivered)
{
  constexpr int kThreads = 4;
  constexpr int kMessagesPerThread = 2000;
  Recorder recorder;
  std::atomic<int> otherCalls{0};
  vpHSlamLog::setSink(recorder.sink());
  vpHSlamLog::setLevel(vpHSlamLog::debug);

  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([t] {
      for (int i = 0; i < kMessagesPerThread; ++i) {
        VP_HSLAM_LOG(vpHSlamLog::debug, "thread " << t << " message " << i);
      }
    });
  }
  // Meanwhile, swap between two sinks: one is always installed, so every message reaches exactly one of them.
  for (int k = 0; k < 200; ++k) {
    vpHSlamLog::setSink([&otherCalls](vpHSlamLog::Level, const std::string &) { ++otherCalls; });
    vpHSlamLog::setSink(recorder.sink());
  }
  for (std::thread &thread : threads) {
    thread.join();
  }
  EXPECT_EQ(static_cast<int>(recorder.messages.size()) + otherCalls.load(), kThreads * kMessagesPerThread);
}
