#include "bench/io/output_files.h"

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "bench/io/model_loader.h"
#include "calib/common/errors.h"

namespace twin {
namespace {
namespace fs = std::filesystem;

fs::path Fresh(const std::string& name) {
  const fs::path d = fs::path(::testing::TempDir()) / ("output_files_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ValidateOutputFolder, RefusesPathsThatCannotBeAReplaceableFolder) {
  const fs::path d = Fresh("folder");
  std::ofstream(d / "file.txt") << "x";
  for (const std::string& bad : {std::string(""), std::string("."), std::string(".."),
                                std::string("/"), std::string("a/.."), std::string("a/./"),
                                (d / "file.txt").string(), (d / "file.txt" / "sub").string()}) {
    const std::string msg = ErrorOf([&] { ValidateOutputFolder(bad, "--out"); });
    EXPECT_NE(msg.find("--out"), std::string::npos) << "'" << bad << "': " << msg;
  }
  EXPECT_NO_THROW(ValidateOutputFolder((d / "new").string(), "--out"));
  EXPECT_NO_THROW(ValidateOutputFolder((d / "new" / "deeper").string(), "--out"));
  EXPECT_NO_THROW(ValidateOutputFolder(d.string() + "/", "--out"));  // an existing folder
}

TEST(ValidateOutputFile, RefusesFoldersAndMissingParents) {
  const fs::path d = Fresh("file");
  for (const std::string& bad : {std::string(""), d.string(), d.string() + "/",
                                (d / "missing" / "x.xml").string()}) {
    EXPECT_NE(ErrorOf([&] { ValidateOutputFile(bad, "--junit"); }).find("--junit"),
              std::string::npos)
        << bad;
  }
  EXPECT_NO_THROW(ValidateOutputFile((d / "x.xml").string(), "--junit"));
  EXPECT_NO_THROW(ValidateOutputFile("relative.xml", "--junit"));
}

TEST(IsSafeName, AcceptsIdentifiersOnly) {
  for (const char* ok : {"r1", "R_2", "_x", "robot_with_a_long_name"}) EXPECT_TRUE(IsSafeName(ok));
  for (const char* bad : {"", "../evil", "a/b", "1r", "r 1", "r.1", "..", "r\n",
                          "a-b"}) {
    EXPECT_FALSE(IsSafeName(bad)) << bad;
  }
  EXPECT_FALSE(IsSafeName(std::string(65, 'a')));
  const std::string msg = ErrorOf([] { RequireSafeName("../evil", "--robot", "robot name"); });
  EXPECT_NE(msg.find("--robot"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'../evil'"), std::string::npos) << msg;
}

TEST(Staging, CreatePublishAndDiscard) {
  const fs::path d = Fresh("staging");
  const std::string out = (d / "out").string();
  std::ofstream(out + ".partial") << "left by a killed run";  // replaced
  const std::string staging = CreateStagingDirectory(out);
  EXPECT_EQ(staging, out + ".partial");
  EXPECT_TRUE(fs::is_directory(staging));
  std::ofstream(fs::path(staging) / "a.txt") << "a";
  PublishDirectory(staging, out);
  EXPECT_TRUE(fs::exists(fs::path(out) / "a.txt"));
  EXPECT_FALSE(fs::exists(staging));
  // A second run replaces the folder as a whole.
  const std::string again = CreateStagingDirectory(out);
  std::ofstream(fs::path(again) / "b.txt") << "b";
  PublishDirectory(again, out);
  EXPECT_FALSE(fs::exists(fs::path(out) / "a.txt"));
  EXPECT_TRUE(fs::exists(fs::path(out) / "b.txt"));
  EXPECT_FALSE(fs::exists(out + ".old"));
  // A discarded staging folder leaves nothing.
  const std::string third = CreateStagingDirectory((d / "other").string());
  std::ofstream(fs::path(third) / "c.txt") << "c";
  DiscardStaging(third);
  EXPECT_FALSE(fs::exists(third));
  EXPECT_FALSE(fs::exists(d / "other"));
}

}  // namespace
}  // namespace twin
