// write_file_atomic: the whole new file or the old one, never a prefix, and an error
// naming the path (issue 13: atomic writes on a full disk).
#include <metariver/io.h>

#include <gtest/gtest.h>
#include "small_disk.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>
#include "require.h"

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

class WriteFileAtomic : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("metariver_io_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
                std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    /// Names in `dir`, sorted.
    static std::vector<std::string> names(const fs::path& dir) {
        std::vector<std::string> n;
        for (const auto& e : fs::directory_iterator(dir)) n.push_back(e.path().filename().string());
        std::sort(n.begin(), n.end());
        return n;
    }

    fs::path dir_;
};

TEST_F(WriteFileAtomic, WritesTheWholeFileAndReplacesAnOldOne) {
    const fs::path p = dir_ / "a.txt";
    ASSERT_TRUE(mr::write_file_atomic(p.string(), "old").ok());
    const std::string big(300'000, 'x');
    ASSERT_TRUE(mr::write_file_atomic(p.string(), big).ok());
    EXPECT_EQ(slurp(p), big);
    EXPECT_EQ(names(dir_), std::vector<std::string>{"a.txt"}) << "no temporary left";
}

TEST_F(WriteFileAtomic, AFullDiskKeepsTheOldFileLeavesNoTemporaryAndNamesThePath) {
    mr::test::SmallDisk disk(dir_ / "disk", 64 * 1024);
    if (!disk.mounted()) MR_SKIP_OR_FAIL(disk.why());
    const fs::path p = disk.dir() / "stats.json";
    ASSERT_TRUE(mr::write_file_atomic(p.string(), "{\"old\": true}\n").ok());
    auto s = mr::write_file_atomic(p.string(), std::string(100 * 1024, 'x'));  // more than the disk holds
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.error().message.find(p.string()), std::string::npos) << s.error().message;
    EXPECT_NE(s.error().message.find("No space left on device"), std::string::npos) << s.error().message;
    EXPECT_EQ(slurp(p), "{\"old\": true}\n") << "the old file must survive whole";
    EXPECT_EQ(names(disk.dir()), std::vector<std::string>{"stats.json"}) << "no temporary left";
    // And the space is free again: a write that fits succeeds.
    EXPECT_TRUE(mr::write_file_atomic(p.string(), std::string(32 * 1024, 'y')).ok());
}

TEST_F(WriteFileAtomic, AFolderInTheWayIsAnErrorNamingThePathAndLeavesNoTemporary) {
    // Where the file should go, something that cannot be replaced (a folder with a file
    // in it): the rename fails after the data was written.
    const fs::path p = dir_ / "frame.png";
    fs::create_directories(p / "inside");
    auto s = mr::write_file_atomic(p.string(), "data");
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.error().message.find(p.string()), std::string::npos) << s.error().message;
    EXPECT_EQ(names(dir_), std::vector<std::string>{"frame.png"}) << "no temporary left";
    EXPECT_TRUE(fs::is_directory(p));
}

TEST_F(WriteFileAtomic, AMissingFolderIsAnErrorNamingThePath) {
    const fs::path p = dir_ / "no" / "such" / "s.json";
    auto s = mr::write_file_atomic(p.string(), "data");
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.error().message.find(p.string()), std::string::npos) << s.error().message;
    EXPECT_EQ(s.error().message.find('\n'), std::string::npos);
}

}  // namespace
