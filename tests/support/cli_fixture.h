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
#include <unistd.h>

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

/// Runs `cmd` in a shell, capturing its exit code, stdout and stderr (through files in
/// `scratch`, removed afterwards).
inline CliResult run_shell(const std::string& cmd, const std::filesystem::path& scratch) {
    const std::filesystem::path out = scratch / "stdout.txt", err = scratch / "stderr.txt";
    const int status = std::system((cmd + " >" + out.string() + " 2>" + err.string()).c_str());
    CliResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    std::filesystem::remove(out);
    std::filesystem::remove(err);
    return r;
}

class CliFixture : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        // The pid keeps two suites (e.g. the default and the asan build) run at the same
        // time on one machine out of each other's folders.
        dir_ = std::filesystem::temp_directory_path() /
               ("metariver_" + std::string(info->test_suite_name()) + "_" + std::string(info->name()) + "_" +
                std::to_string(::getpid()));
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    /// Runs `prefix METARIVER_EXE args` in a shell (prefix: environment or `cd DIR &&`).
    CliResult run(const std::string& args, const std::string& prefix = "") {
        return run_shell(prefix + " " + std::string(METARIVER_EXE) + " " + args, dir_);
    }

    std::filesystem::path dir_;
};

}  // namespace mr::test
