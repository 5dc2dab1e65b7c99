// The plotting layer: nice ticks (Heckbert 1990) on hand-checked ranges, the colour map's ends,
// and that a figure with every element encodes as PNG and SVG.

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "cairn/viz/color.hpp"
#include "cairn/viz/render.hpp"
#include "cairn/viz/ticks.hpp"

namespace cairn::viz {
namespace {

TEST(Ticks, NiceNumbersOnHandCheckedRanges) {
  const Ticks a = nice_ticks(0, 1, 6);  // range 1 -> step nice(1/5 = 0.2) = 0.2
  EXPECT_DOUBLE_EQ(a.step, 0.2);
  EXPECT_EQ(a.decimals, 1);
  ASSERT_EQ(a.values.size(), 6u);
  EXPECT_DOUBLE_EQ(a.values[3], 0.6);
  const Ticks b = nice_ticks(-48.3, 31.7, 5);  // range 80 -> nice(80) = 100 -> step nice(25) = 20
  EXPECT_DOUBLE_EQ(b.step, 20);
  EXPECT_EQ(b.decimals, 0);
  EXPECT_EQ(b.values, (std::vector<double>{-40, -20, 0, 20}));
  const Ticks c = nice_ticks(3, 3);
  EXPECT_EQ(c.values.size(), 1u);
  EXPECT_EQ(format_tick(-0.0001, 2), "0.00");  // no "-0.00"
  EXPECT_EQ(format_tick(0.25, 2), "0.25");
}

TEST(Color, ViridisEnds) {
  const Rgb lo = viridis(0);
  const Rgb hi = viridis(1);
  EXPECT_NEAR(lo.r, 0x44 / 255.0, 1e-12);
  EXPECT_NEAR(lo.b, 0x54 / 255.0, 1e-12);
  EXPECT_NEAR(hi.g, 0xE7 / 255.0, 1e-12);
  EXPECT_NEAR(viridis(2).r, hi.r, 0);  // clamped
  EXPECT_NEAR(viridis(std::nan("")).r, lo.r, 0);
}

Figure every_element() {
  Figure f;
  f.title = "test";
  f.columns = 2;
  Axes lines;
  lines.title = "lines";
  lines.x_label = "x [m]";
  lines.y_label = "y [m]";
  lines.equal_aspect = true;
  Series s;
  s.label = "estimate";
  for (int i = 0; i < 50; ++i) {
    s.x.push_back(std::cos(i * 0.1));
    s.y.push_back(std::sin(i * 0.1));
    s.values.push_back(i);
  }
  s.x[10] = std::nan("");  // a gap, not a failure
  lines.series.push_back(s);
  lines.color_bar = ColorBar{"error [m]", 0, 49};
  lines.horizontal_lines.push_back({"mean", 0.5, kBlack, true});
  Axes bars;
  bars.categories = {"100", "200"};
  bars.bars.push_back({"t_err", {1.0, 0.5}, categorical(0)});
  bars.bar_value_decimals = 2;
  f.panels = {lines, bars, Axes{}};
  return f;
}

TEST(Render, PngAndSvgEncode) {
  const RenderResult png = render(every_element(), ImageFormat::kPng);
  ASSERT_TRUE(png.ok) << png.message;
  ASSERT_GT(png.bytes.size(), 1000u);
  EXPECT_EQ(png.bytes.substr(1, 3), "PNG");
  const RenderResult svg = render(every_element(), ImageFormat::kSvg);
  ASSERT_TRUE(svg.ok) << svg.message;
  EXPECT_NE(svg.bytes.find("<svg"), std::string::npos);
  Figure tiny;
  tiny.width_px = 0;
  const RenderResult bad = render(tiny, ImageFormat::kPng);
  EXPECT_FALSE(bad.ok);
  EXPECT_FALSE(bad.message.empty());
}

TEST(Render, FormatFromExtension) {
  EXPECT_EQ(image_format_from_path("a/b.PNG"), ImageFormat::kPng);
  EXPECT_EQ(image_format_from_path("b.svg"), ImageFormat::kSvg);
  EXPECT_FALSE(image_format_from_path("b.pdf").has_value());
  EXPECT_FALSE(image_format_from_path("noext").has_value());
}

}  // namespace
}  // namespace cairn::viz
