// A test with a folder of its own: /tmp/visaudit-PREFIX-PID-TESTNAME, created empty before the
// test and removed after it (the tests that write files or run the program in it).
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <utility>

namespace va::testing_util {

class TempDirTest : public ::testing::Test {
  protected:
    explicit TempDirTest(std::string prefix) : prefix_(std::move(prefix)) {}
    void SetUp() override {
        const auto *info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = std::filesystem::temp_directory_path() /
               ("visaudit-" + prefix_ + "-" + std::to_string(getpid()) + "-" + info->name());
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    std::filesystem::path dir_;

  private:
    std::string prefix_;
};

}  // namespace va::testing_util
