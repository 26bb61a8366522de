// Wall and fluid lattices from geometry/shapes: counts and positions against the lattice they
// continue (exact arithmetic on a regular lattice, tolerance 1e-12 m for float round-off in double).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "geometry/shapes.hpp"

using turbid::geometry::Aabb;
using turbid::geometry::Point;

TEST(Shapes, FillBoxPlacesCellCentres) {
  const auto pts = turbid::geometry::fill_box(Aabb{{0, 0, 0}, {1.0, 0.5, 0}}, 0.1, 2);
  ASSERT_EQ(pts.size(), 50u);  // 10 x 5 cells
  EXPECT_NEAR(pts.front()[0], 0.05, 1e-12);
  EXPECT_NEAR(pts.front()[1], 0.05, 1e-12);
  EXPECT_NEAR(pts.back()[0], 0.95, 1e-12);
  EXPECT_NEAR(pts.back()[1], 0.45, 1e-12);
}

// A closed 1 x 1 tank with 2 layers: a 14 x 14 lattice minus the 10 x 10 interior = 96 points;
// open at +y: rows above the top are left out, 14 x 12 - 10 x 10 = 68.
TEST(Shapes, ContainerWallsCountAndOpenFaces) {
  const Aabb box{{0, 0, 0}, {1.0, 1.0, 0}};
  const auto closed = turbid::geometry::container_walls(box, 0.1, 2, 2, {false, false, false, false, false, false});
  EXPECT_EQ(closed.size(), 96u);
  const auto open = turbid::geometry::container_walls(box, 0.1, 2, 2, {false, false, false, true, false, false});
  EXPECT_EQ(open.size(), 68u);
  for (const Point& p : open) EXPECT_LT(p[1], 1.0) << "no wall above an open top";
  // Every wall point lies outside the box, and the nearest ones are dx/2 from its faces, i.e. dx
  // from the first fluid row of fill_box.
  double nearest = 1e9;
  for (const Point& p : closed) {
    const bool inside = p[0] > 0 && p[0] < 1 && p[1] > 0 && p[1] < 1;
    EXPECT_FALSE(inside);
    nearest = std::min({nearest, std::abs(p[0] + 0.05), std::abs(p[1] + 0.05)});
  }
  EXPECT_NEAR(nearest, 0.0, 1e-12);
}

// A 1 m segment along +x at dx = 0.1 with 2 layers: 10 points per layer at y = -0.05 and -0.15 on
// the right of travel, +0.05 and +0.15 on the left.
TEST(Shapes, PolylineWallsLayersOnTheChosenSide) {
  const std::vector<Point> line{{0, 0, 0}, {1, 0, 0}};
  const auto right = turbid::geometry::polyline_walls(line, false, 0.1, 2, -1);
  ASSERT_EQ(right.size(), 20u);
  for (const Point& p : right) {
    EXPECT_TRUE(std::abs(p[1] + 0.05) < 1e-12 || std::abs(p[1] + 0.15) < 1e-12) << p[1];
    EXPECT_GT(p[0], 0.0);
    EXPECT_LT(p[0], 1.0);
  }
  const auto left = turbid::geometry::polyline_walls(line, false, 0.1, 2, +1);
  for (const Point& p : left) EXPECT_GT(p[1], 0.0);
}

// A shell of one layer of a 0.5 x 0.5 x 0.5 box at dx = 0.1: 5^3 - 3^3 = 98 points.
TEST(Shapes, BoxShellKeepsOnlyTheOuterLayers) {
  const Aabb box{{0, 0, 0}, {0.5, 0.5, 0.5}};
  EXPECT_EQ(turbid::geometry::box_shell(box, 0.1, 3, 1).size(), 98u);
  EXPECT_EQ(turbid::geometry::box_shell(box, 0.1, 3, 0).size(), 125u);  // layers <= 0: full
}

// Extrusion across y: the section's points on the rows a fluid box of the same y extent fills
// (fill_box's rule), here 0.15 m at dx = 0.040625 m: round(3.69) = 4 rows at (k + 1/2) dx, the
// x-z coordinates of the section kept.
TEST(Shapes, ExtrusionRepeatsTheSectionOnTheRowsOfABox) {
  const double dx = 0.040625;
  const std::vector<Point> section{{0.1, 1.5, 0}, {0.3, 0.2, 0}};  // (x, z)
  const auto pts = turbid::geometry::extrude_across_y(section, 0.0, 0.15, dx);
  const auto rows = turbid::geometry::fill_box(Aabb{{0, 0, 0}, {dx, 0.15, dx}}, dx, 3);  // one column
  ASSERT_EQ(rows.size(), 4u);
  ASSERT_EQ(pts.size(), section.size() * rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k)
    for (std::size_t i = 0; i < section.size(); ++i) {
      const Point& p = pts[k * section.size() + i];
      EXPECT_EQ(p[0], section[i][0]);
      EXPECT_NEAR(p[1], rows[k][1], 1e-12);
      EXPECT_EQ(p[2], section[i][1]);
    }
  EXPECT_THROW(turbid::geometry::extrude_across_y(section, 0.15, 0.0, dx), std::invalid_argument);
}
