#include "bench/report/output_mark.h"

#include <gtest/gtest.h>

namespace twin {
namespace {

TEST(OutputMarkTest, TextNamesTheVerbAndReadsBack) {
  const std::string text = OutputMarkText("study");
  EXPECT_EQ(text, "{\"verb\":\"study\",\"written_by\":\"twinbench\"}\n");
  EXPECT_EQ(OutputMarkVerb(text), "study");
}

TEST(OutputMarkTest, AnythingButOurMarkNamesNoVerb) {
  EXPECT_EQ(OutputMarkVerb(""), "");
  EXPECT_EQ(OutputMarkVerb("not json"), "");
  EXPECT_EQ(OutputMarkVerb("[\"run\"]"), "");
  EXPECT_EQ(OutputMarkVerb(R"({"written_by": "someone", "verb": "run"})"), "");
  EXPECT_EQ(OutputMarkVerb(R"({"written_by": 3, "verb": "run"})"), "");
  EXPECT_EQ(OutputMarkVerb(R"({"written_by": "twinbench", "verb": 1})"), "");
  EXPECT_EQ(OutputMarkVerb(R"({"written_by": "twinbench"})"), "");
}

}  // namespace
}  // namespace twin
