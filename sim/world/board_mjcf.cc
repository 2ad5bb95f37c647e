#include "sim/world/board_mjcf.h"

#include <algorithm>
#include <cassert>
#include <sstream>

#include "calib/common/text_format.h"

namespace twin {
namespace {

constexpr const char* kPrintTexture = "twin_board_print_tex";
constexpr const char* kPrintMaterial = "twin_board_print";
constexpr const char* kPlateMaterial = "twin_board_plate";
constexpr int kTextureSize = 512;  // texels per 2x2-square period: 256 per square

// Where the squares lie in frame T.
struct Layout {
  int nx, ny;      // squares
  int mx, my;      // squares on the print box (even: nx, ny rounded up)
  double s;        // square side [m]
  double x0, y0;   // the (-x, -y) corner of the squares [m]
};

Layout MakeLayout(const BoardSpec& b) {
  assert(b.squares_x >= 2 && b.squares_y >= 2 && b.square_m > 0);
  Layout l;
  l.nx = b.squares_x;
  l.ny = b.squares_y;
  l.mx = l.nx + l.nx % 2;
  l.my = l.ny + l.ny % 2;
  l.s = b.square_m;
  l.x0 = -(l.nx / 2) * l.s;
  l.y0 = -(l.ny / 2) * l.s;
  return l;
}

std::string Num(double v) { return ShortestNumber(v); }

std::string Vec3(double x, double y, double z) { return Num(x) + " " + Num(y) + " " + Num(z); }

// A box geom centred at (x, y, z) with half sizes (hx, hy, hz); `extra` adds attributes.
std::string BoxGeom(const std::string& name, double x, double y, double z, double hx, double hy,
                    double hz, const std::string& material, const std::string& extra) {
  return "<geom name=\"" + name + "\" type=\"box\" pos=\"" + Vec3(x, y, z) + "\" size=\"" +
         Vec3(hx, hy, hz) + "\" material=\"" + material + "\" " + extra + "/>\n";
}

// The builtin checker's first colour fills the texture's (row < h/2, col < w/2) quadrant. With
// the box texgen, the print box's (-x, -y) corner square gets that colour iff mx/2 + my/2 is
// odd (worked out from s, t at the box corner; the render test checks it), so choose rgb1 to
// make that square black.
bool CornerIsFirstColour(const Layout& l) { return (l.mx / 2 + l.my / 2) % 2 == 1; }

}  // namespace

std::string BoardAssetsMjcf(const BoardSpec& board) {
  const Layout l = MakeLayout(board);
  const bool black_first = CornerIsFirstColour(l);
  std::ostringstream out;
  out << "<texture name=\"" << kPrintTexture << "\" type=\"2d\" builtin=\"checker\" width=\""
      << kTextureSize << "\" height=\"" << kTextureSize << "\" rgb1=\""
      << (black_first ? "0 0 0" : "1 1 1") << "\" rgb2=\"" << (black_first ? "1 1 1" : "0 0 0")
      << "\"/>\n";
  // texrepeat: one texture period is 2 squares, the unit box spans mx (my) squares.
  out << "<material name=\"" << kPrintMaterial << "\" texture=\"" << kPrintTexture
      << "\" texrepeat=\"" << Num(l.mx / 2) << " " << Num(l.my / 2)
      << "\" rgba=\"1 1 1 1\" specular=\"0\" shininess=\"0\" reflectance=\"0\"/>\n";
  out << "<material name=\"" << kPlateMaterial
      << "\" rgba=\"1 1 1 1\" specular=\"0\" shininess=\"0\" reflectance=\"0\"/>\n";
  return out.str();
}

std::string BoardGeomsMjcf(const BoardSpec& board, const std::string& prefix) {
  const Layout l = MakeLayout(board);
  const double gap = kBoardLayerGap;
  const std::string visual = "contype=\"0\" conaffinity=\"0\" mass=\"0\"";
  // Plate: white, carries the mass; front face kBoardLayerGap behind the printed face. On the
  // +x (+y) side of an odd count it reaches past the cover strip, keeping the outline square.
  const double m = board.margin_m;
  const double mx = l.nx % 2 ? std::max(m, l.s) : m, my = l.ny % 2 ? std::max(m, l.s) : m;
  const double x_lo = l.x0 - m, x_hi = l.x0 + l.nx * l.s + mx;
  const double y_lo = l.y0 - m, y_hi = l.y0 + l.ny * l.s + my;
  std::string xml = BoxGeom(prefix + "plate", (x_lo + x_hi) / 2, (y_lo + y_hi) / 2,
                            -gap - board.thickness_m / 2, (x_hi - x_lo) / 2, (y_hi - y_lo) / 2,
                            board.thickness_m / 2, kPlateMaterial,
                            "mass=\"" + Num(board.mass_kg) + "\"");
  // Print: front face at z = 0, centre on a square boundary (even mx, my).
  const double pw = l.mx * l.s, ph = l.my * l.s;
  xml += BoxGeom(prefix + "print", l.x0 + pw / 2, l.y0 + ph / 2, -gap, pw / 2, ph / 2, gap,
                 kPrintMaterial, visual);
  // Odd counts: white strips in front of the extra column / row of the print box.
  if (l.nx % 2 == 1) {
    xml += BoxGeom(prefix + "cover_x", l.x0 + (l.nx + 0.5) * l.s, l.y0 + ph / 2, 0, l.s / 2,
                   ph / 2, gap, kPlateMaterial, visual);
  }
  if (l.ny % 2 == 1) {
    xml += BoxGeom(prefix + "cover_y", l.x0 + pw / 2, l.y0 + (l.ny + 0.5) * l.s, 0, pw / 2,
                   l.s / 2, gap, kPlateMaterial, visual);
  }
  return xml;
}

std::vector<Vector3> BoardInnerCorners(const BoardSpec& board) {
  const Layout l = MakeLayout(board);
  std::vector<Vector3> corners;
  corners.reserve(static_cast<size_t>((l.nx - 1) * (l.ny - 1)));
  for (int j = 1; j < l.ny; ++j) {
    for (int i = 1; i < l.nx; ++i) corners.emplace_back(l.x0 + i * l.s, l.y0 + j * l.s, 0.0);
  }
  return corners;
}

}  // namespace twin
