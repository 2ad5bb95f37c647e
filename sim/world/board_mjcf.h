// MJCF text of the calibration chessboard (BoardSpec), and its inner corners in the board frame.
//
// Board frame T (twin_spec.h): origin at the feature point P, on the printed face, z out of the
// face, x along a row of squares, y = z x x. With nx = squares_x, ny = squares_y the squares
// cover x in [-(nx/2) s, (nx - nx/2) s] and y likewise (integer division, s = square_m), so P
// is the centre inner corner for even counts and, for an odd count, the inner corner nearest
// the centre on the -x (-y) side. The square at the board's (-x, -y) corner is black.
//
// Construction (DESIGN.md: a textured box is the most accurate chessboard): a white plate box
// (mass_kg, collidable) whose front face lies kLayerGap behind the printed face, and a thin
// "print" box whose front face is the printed face, textured with MuJoCo's builtin 2x2 checker.
// MuJoCo 2.2.2 maps a 2D texture onto a box by object-linear texgen, s = 0.5 rx x - 0.5 and
// t = -0.5 ry y - 0.5 over the unit box (x, y in [-1, 1]), so with texrepeat (m/2, n/2) the box
// shows m x n squares and its centre is always a square boundary. That needs an even count, so
// for an odd count the print box gets one extra row/column of squares on the +x (+y) side, and a
// white cover strip kLayerGap in front of the face hides it (the white border on that side is
// then max(margin, square) wide). Print and strips are visual only (no contacts, no mass).
#pragma once

#include <string>
#include <vector>

#include "calib/common/frames.h"
#include "sim/world/twin_spec.h"

namespace twin {

/// Depth step between the board's layers (plate, print, cover strip) [m]; far above the depth
/// buffer resolution at working distances (about 1 um at 0.6 m with a 2 cm near plane).
constexpr double kBoardLayerGap = 5e-5;

/// The <texture> and <material> elements of the board, to put inside <asset>. Names are fixed
/// ("twin_board_print_tex", "twin_board_print", "twin_board_plate"): one board per model.
std::string BoardAssetsMjcf(const BoardSpec& board);

/// The <geom> elements of the board, to put inside a body whose frame is the board frame T.
/// Geom names start with `prefix` (e.g. "board_" gives "board_plate", "board_print").
std::string BoardGeomsMjcf(const BoardSpec& board, const std::string& prefix);

/// The (squares_x - 1) x (squares_y - 1) inner corners in frame T [m], row-major: index
/// j * (squares_x - 1) + i is the corner at x = (i + 1 - squares_x/2) s,
/// y = (j + 1 - squares_y/2) s, z = 0 (integer division). Not OpenCV's detection order.
std::vector<Vector3> BoardInnerCorners(const BoardSpec& board);

}  // namespace twin
