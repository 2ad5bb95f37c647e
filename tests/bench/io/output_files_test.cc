#include "bench/io/output_files.h"

#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bench/io/model_loader.h"
#include "calib/common/errors.h"

namespace twin {
namespace {
namespace fs = std::filesystem;

std::string ReadBack(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

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
  fs::create_directories(d / "empty");
  EXPECT_NO_THROW(ValidateOutputFolder((d / "empty").string() + "/", "--out"));  // holds nothing
}

// The output-safety rule (issue 38): only new, empty or marked folders of the same verb; the
// staging siblings only when marked; never over or inside an input.
TEST(ValidateOutputFolder, WritesOnlyNewEmptyOrItsOwnMarkedFolders) {
  const fs::path d = Fresh("owned");
  SetOutputVerb("run");
  fs::create_directories(d / "users");
  std::ofstream(d / "users" / "thesis.tex") << "years of work";
  std::string msg = ErrorOf([&] { ValidateOutputFolder((d / "users").string(), "--out"); });
  EXPECT_NE(msg.find("--out: '" + (d / "users").string() + "' is a folder twinbench did not "
                     "write"), std::string::npos) << msg;
  // Marked by the same verb: accepted (a rerun); by another verb: refused, naming it.
  fs::create_directories(d / "ours");
  std::ofstream(d / "ours" / "report.json") << "{}";
  MarkFolder((d / "ours").string());
  EXPECT_TRUE(IsMarkedFolder((d / "ours").string(), "run"));
  EXPECT_NO_THROW(ValidateOutputFolder((d / "ours").string(), "--out"));
  MarkFolder((d / "ours").string(), "study");
  msg = ErrorOf([&] { ValidateOutputFolder((d / "ours").string(), "--out"); });
  EXPECT_NE(msg.find("holds the output of `twinbench study`, not of `twinbench run`"),
            std::string::npos) << msg;
  // A mark that is not ours (hand-written, another program's) does not count.
  fs::create_directories(d / "forged");
  std::ofstream(d / "forged" / kOutputMarker) << "{\"verb\": \"run\"}";
  EXPECT_NE(ErrorOf([&] { ValidateOutputFolder((d / "forged").string(), "--out"); }), "");
  // A symbolic link, even to a folder of ours, is refused: the publishing rename would replace it.
  fs::create_directory_symlink(d / "ours", d / "link");
  msg = ErrorOf([&] { ValidateOutputFolder((d / "link").string(), "--out"); });
  EXPECT_NE(msg.find("is a symbolic link"), std::string::npos) << msg;
  // The staging siblings: a user's NEW.partial or NEW.old makes the verb refuse.
  for (const char* suffix : {".partial", ".old"}) {
    const fs::path sibling = d / (std::string("new") + suffix);
    std::ofstream(sibling) << "the user's";
    msg = ErrorOf([&] { ValidateOutputFolder((d / "new").string(), "--out"); });
    EXPECT_NE(msg.find("twinbench stages its output under that name"), std::string::npos) << msg;
    fs::remove(sibling);
  }
  EXPECT_NO_THROW(ValidateOutputFolder((d / "new").string(), "--out"));
  // Nothing was changed by any check.
  EXPECT_EQ(ReadBack(d / "users" / "thesis.tex"), "years of work");
  SetOutputVerb("twinbench");
}

TEST(ValidateOutputFolder, NeverEqualsContainsOrLiesInsideAnInput) {
  const fs::path d = Fresh("inputs");
  SetOutputVerb("identify");
  fs::create_directories(d / "job" / "data");
  std::ofstream(d / "job" / "data" / "m.csv") << "x";
  MarkFolder((d / "job").string());  // an earlier output the user keeps an input in
  NoteInput((d / "job" / "data" / "m.csv").string());
  std::string msg = ErrorOf([&] { ValidateOutputFolder((d / "job").string(), "--out"); });
  EXPECT_NE(msg.find("contains the input '" + (d / "job" / "data" / "m.csv").string() + "'"),
            std::string::npos) << msg;
  NoteInput((d / "shard").string(), true);
  msg = ErrorOf([&] { ValidateOutputFolder((d / "shard" / "merged").string(), "--out"); });
  EXPECT_NE(msg.find("lies inside the input folder"), std::string::npos) << msg;
  msg = ErrorOf([&] { ValidateOutputFile((d / "job" / "data" / "m.csv").string(), "--junit",
                                         {"x"}); });
  EXPECT_NE(msg.find("is the input"), std::string::npos) << msg;
  EXPECT_NO_THROW(ValidateOutputFolder((d / "elsewhere").string(), "--out"));
  SetOutputVerb("twinbench");
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

TEST(ValidateOutputFile, ReplacesOnlyRegularFilesTwinbenchWrote) {
  const fs::path d = Fresh("file_owned");
  std::ofstream(d / "scenario.yaml") << "scenario: {name: mine}";
  std::ofstream(d / "old.xml") << "<?xml version=\"1.0\"?>\n" << kWrittenByComment << "\n<a/>";
  const std::vector<std::string> sig = {kWrittenByComment};
  std::string msg = ErrorOf([&] { ValidateOutputFile((d / "scenario.yaml").string(), "--junit",
                                                     sig); });
  EXPECT_NE(msg.find("was not written by twinbench"), std::string::npos) << msg;
  EXPECT_NO_THROW(ValidateOutputFile((d / "old.xml").string(), "--junit", sig));
  // With no signature (a CSV carries no mark) every existing file is refused.
  msg = ErrorOf([&] { ValidateOutputFile((d / "old.xml").string(), "--out"); });
  EXPECT_NE(msg.find("exists; twinbench writes only a new file"), std::string::npos) << msg;
  // Devices, FIFOs and links are never written, whatever they point to.
  for (const std::string& special : {std::string("/dev/null"), std::string("/dev/zero")}) {
    msg = ErrorOf([&] { ValidateOutputFile(special, "--junit", sig); });
    EXPECT_NE(msg.find("is a character device"), std::string::npos) << msg;
  }
  ASSERT_EQ(mkfifo((d / "fifo").c_str(), 0644), 0);
  msg = ErrorOf([&] { ValidateOutputFile((d / "fifo").string(), "--junit", sig); });
  EXPECT_NE(msg.find("is a FIFO"), std::string::npos) << msg;
  fs::create_symlink(d / "old.xml", d / "link.xml");
  msg = ErrorOf([&] { ValidateOutputFile((d / "link.xml").string(), "--junit", sig); });
  EXPECT_NE(msg.find("is a symbolic link"), std::string::npos) << msg;
  EXPECT_EQ(ReadBack(d / "scenario.yaml"), "scenario: {name: mine}");
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
  // A user's file under the staging name is refused and kept; a staging folder left by a
  // killed run (marked) is replaced.
  std::ofstream(out + ".partial") << "the user's";
  EXPECT_NE(ErrorOf([&] { CreateStagingDirectory(out); }), "");
  EXPECT_EQ(ReadBack(out + ".partial"), "the user's");
  fs::remove(out + ".partial");
  fs::create_directories(out + ".partial");
  std::ofstream(fs::path(out + ".partial") / "half.png") << "x";
  MarkFolder(out + ".partial");
  const std::string staging = CreateStagingDirectory(out);
  EXPECT_FALSE(fs::exists(fs::path(staging) / "half.png"));
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
