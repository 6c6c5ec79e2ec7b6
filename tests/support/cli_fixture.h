// A test fixture for end-to-end tests of the metariver binary: a fresh temporary folder
// per test, and a runner that captures exit code, stdout and stderr.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>

namespace mr::test {

struct CliResult {
    int code = -1;
    std::string out;
    std::string err;
};

inline std::string slurp(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

class CliFixture : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = std::filesystem::temp_directory_path() /
               ("metariver_" + std::string(info->test_suite_name()) + "_" + std::string(info->name()));
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    /// Runs `prefix METARIVER_EXE args` in a shell (prefix: environment or `cd DIR &&`).
    CliResult run(const std::string& args, const std::string& prefix = "") {
        const std::filesystem::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
        const std::string cmd =
            prefix + " " + std::string(METARIVER_EXE) + " " + args + " >" + out.string() + " 2>" + err.string();
        const int status = std::system(cmd.c_str());
        CliResult r;
        r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        r.out = slurp(out);
        r.err = slurp(err);
        std::filesystem::remove(out);
        std::filesystem::remove(err);
        return r;
    }

    std::filesystem::path dir_;
};

}  // namespace mr::test
