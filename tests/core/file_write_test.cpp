// write_file_atomically: a file is either the old one or the whole new one, whatever fails.

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "hof/core/file_write.h"

namespace hof {
namespace {

namespace fs = std::filesystem;

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class FileWrite : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hof-file-write-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  /// Files in the folder other than `keep` (temporaries left behind).
  [[nodiscard]] int others(const fs::path& keep) const {
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir_)) n += e.path() != keep ? 1 : 0;
    return n;
  }
  fs::path dir_;
};

TEST_F(FileWrite, WritesAndReplacesWholeFilesKeepingTheirMode) {
  const fs::path file = dir_ / "project.hof";
  ASSERT_TRUE(write_file_atomically(file, "first"));
  EXPECT_EQ(read_all(file), "first");
  fs::permissions(file, fs::perms::owner_read | fs::perms::owner_write);
  ASSERT_TRUE(write_file_atomically(file, std::string(100000, 'x')));
  EXPECT_EQ(read_all(file), std::string(100000, 'x'));
  EXPECT_EQ(fs::status(file).permissions() & fs::perms::all, fs::perms::owner_read | fs::perms::owner_write);
  EXPECT_EQ(others(file), 0);
}

TEST_F(FileWrite, AMissingFolderOrAFolderInTheWayIsAClearErrorAndLeavesNothing) {
  auto missing = write_file_atomically(dir_ / "gone" / "project.hof", "x");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kIo);
  EXPECT_NE(missing.error().to_string().find("gone/project.hof"), std::string::npos) << missing.error().to_string();
  EXPECT_NE(missing.error().message.find("No such file"), std::string::npos) << missing.error().message;
  fs::create_directories(dir_ / "folder");
  EXPECT_FALSE(write_file_atomically(dir_ / "folder", "x"));
  EXPECT_EQ(others(dir_ / "folder"), 0);
}

TEST_F(FileWrite, ADiskThatFillsMidWriteLeavesTheOldFileWhole) {
  // A child process may write 4 KiB per file (RLIMIT_FSIZE; SIGXFSZ ignored, so write(2)
  // fails with EFBIG as it fails with ENOSPC on a full disk) and tries to save 1 MiB.
  const fs::path file = dir_ / "project.hof";
  ASSERT_TRUE(write_file_atomically(file, "the project as it was"));
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{4096, 4096};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    const auto written = write_file_atomically(file, std::string(1 << 20, 'n'));
    ::_exit(written ? 0 : (written.error().message.find("too large") != std::string::npos ? 7 : 8));
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 7) << "the failed save was not reported with the system's reason";
  EXPECT_EQ(read_all(file), "the project as it was");
  EXPECT_EQ(others(file), 0) << "a temporary file was left behind";
}

}  // namespace
}  // namespace hof
