// Test helper: check that a call fails with a given vpHSlamException code and a message naming what failed.
#ifndef HSLAM_TEST_ERRORS_H
#define HSLAM_TEST_ERRORS_H

#include <visp3/hslam/vpHSlamException.h>

#include <gtest/gtest.h>

#include <exception>
#include <functional>
#include <string>
#include <vector>

namespace hslam_test
{
//! Runs \e call and checks it throws vpHSlamException with \e code and a message containing each of \e mustContain.
inline void expectHSlamError(const std::function<void()> &call, vpHSlamException::ErrorCode code,
                             const std::vector<std::string> &mustContain)
{
  try {
    call();
    ADD_FAILURE() << "no exception, expected code " << code;
  } catch (const vpHSlamException &e) {
    EXPECT_EQ(e.getCode(), static_cast<int>(code)) << e.getStringMessage();
    for (const std::string &part : mustContain) {
      EXPECT_NE(e.getStringMessage().find(part), std::string::npos)
          << "message '" << e.getStringMessage() << "' lacks '" << part << "'";
    }
  } catch (const std::exception &e) {
    ADD_FAILURE() << "std::exception instead of vpHSlamException: " << e.what();
  } catch (...) {
    ADD_FAILURE() << "unknown exception instead of vpHSlamException";
  }
}
} // namespace hslam_test

#endif
