// The board's MJCF and inner corners; where the rendered corners land is checked in
// renderer_test.cc.
#include "sim/world/board_mjcf.h"

#include <string>

#include <gtest/gtest.h>

#include "sim/world/mujoco_handles.h"

namespace twin {
namespace {

MjModelPtr BoardModel(const BoardSpec& board) {
  InstallMujocoErrorHandlers();
  return LoadMjcfFromString("<mujoco><asset>" + BoardAssetsMjcf(board) +
                            "</asset><worldbody><body name=\"T\" pos=\"0 0 1\">"
                            "<freejoint/>" + BoardGeomsMjcf(board, "b_") +
                            "</body></worldbody></mujoco>");
}

BoardSpec Board(int nx, int ny) {
  BoardSpec b;
  b.squares_x = nx;
  b.squares_y = ny;
  return b;
}

// Corners are small multiples of the square size: only rounding can differ (1e-15 m).
void ExpectPoint(const Vector3& actual, const Vector3& expected) {
  EXPECT_LT((actual - expected).norm(), 1e-15) << actual.transpose();
}

TEST(BoardInnerCorners, RowMajorAroundTheFeaturePoint) {
  const std::vector<Vector3> c = BoardInnerCorners(Board(4, 4));
  ASSERT_EQ(c.size(), 9u);
  ExpectPoint(c[4], Vector3::Zero());  // centre corner is P
  ExpectPoint(c[0], Vector3(-0.02, -0.02, 0));
  ExpectPoint(c[1], Vector3(0, -0.02, 0));  // x runs fastest
  ExpectPoint(c[3], Vector3(-0.02, 0, 0));
}

TEST(BoardInnerCorners, OddCountsPutThePointOnTheMinusSide) {
  const std::vector<Vector3> c = BoardInnerCorners(Board(5, 3));
  ASSERT_EQ(c.size(), 8u);  // 4 x 2
  ExpectPoint(c[1], Vector3::Zero());  // i = 1, j = 0: nearest the centre
  ExpectPoint(c[0], Vector3(-0.02, 0, 0));
  ExpectPoint(c[7], Vector3(0.04, 0.02, 0));
}

TEST(BoardMjcf, CompilesWithTheSpecMassAndFaceAtZero) {
  for (const BoardSpec& b : {Board(4, 4), Board(5, 4), Board(5, 5)}) {
    const MjModelPtr m = BoardModel(b);
    const int body = mj_name2id(m.get(), mjOBJ_BODY, "T");
    EXPECT_NEAR(m->body_mass[body], b.mass_kg, 1e-12);  // only the plate has mass
    const int print = mj_name2id(m.get(), mjOBJ_GEOM, "b_print");
    const int plate = mj_name2id(m.get(), mjOBJ_GEOM, "b_plate");
    ASSERT_GE(print, 0);
    ASSERT_GE(plate, 0);
    // Printed face at z = 0 of T, plate just behind it (1e-12: MJCF numbers are exact).
    EXPECT_NEAR(m->geom_pos[3 * print + 2] + m->geom_size[3 * print + 2], 0, 1e-12);
    EXPECT_NEAR(m->geom_pos[3 * plate + 2] + m->geom_size[3 * plate + 2], -kBoardLayerGap,
                1e-12);
    EXPECT_EQ(m->geom_contype[print], 0);
    EXPECT_EQ(mj_name2id(m.get(), mjOBJ_GEOM, "b_cover_x") >= 0, b.squares_x % 2 == 1);
    EXPECT_EQ(mj_name2id(m.get(), mjOBJ_GEOM, "b_cover_y") >= 0, b.squares_y % 2 == 1);
    // One texture period per two squares of the (even) print box.
    const int mat = m->geom_matid[print];
    EXPECT_FLOAT_EQ(m->mat_texrepeat[2 * mat], (b.squares_x + b.squares_x % 2) / 2);
    EXPECT_FLOAT_EQ(m->mat_texrepeat[2 * mat + 1], (b.squares_y + b.squares_y % 2) / 2);
  }
}

}  // namespace
}  // namespace twin
