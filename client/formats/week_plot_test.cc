#include "client/formats/week_plot.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace fremen::formats {
namespace {

constexpr double kDay = 86400;

// A week of a daily square wave, sampled hourly, with observations every 6 h.
TimeSeriesPlot DailyWave() {
  TimeSeriesPlot plot;
  plot.title = "door <open>";
  plot.start = 1.7e9;
  plot.end = plot.start + 7 * kDay;
  for (int h = 0; h <= 7 * 24; ++h) {
    const double t = plot.start + h * 3600.0;
    plot.probability.push_back({t, 0.5 + 0.4 * std::sin(2 * M_PI * h / 24.0)});
  }
  for (int i = 0; i < 28; ++i)
    plot.observations.push_back({plot.start + i * 6 * 3600.0 + 1800, i % 2 == 0 ? 1.0 : 0.0});
  plot.observations.push_back({plot.end + 10, 1.0});  // outside: not drawn
  plot.last_observation = plot.start + 3 * kDay;
  return plot;
}

// Checks that every element is closed in order (a small XML well-formedness check: tags balance,
// attributes are quoted).
void ExpectBalancedTags(const std::string& svg) {
  std::vector<std::string> open;
  const std::regex tag(R"(<(/?)([a-zA-Z]+)((?:\s+[a-zA-Z][a-zA-Z0-9:-]*="[^"<]*")*)\s*(/?)>)");
  std::string rest = svg.substr(svg.find("?>") + 2);
  size_t tags = 0;
  for (std::sregex_iterator it(rest.begin(), rest.end(), tag), end; it != end; ++it, ++tags) {
    const std::string name = (*it)[2];
    if ((*it)[1] == "/") {
      ASSERT_FALSE(open.empty()) << "closing " << name << " without an opening";
      ASSERT_EQ(open.back(), name);
      open.pop_back();
    } else if ((*it)[4] != "/") {
      open.push_back(name);
    }
  }
  EXPECT_TRUE(open.empty());
  // Every '<' is the start of a tag the regex accepted (so no malformed element was skipped).
  EXPECT_EQ(tags, static_cast<size_t>(std::count(rest.begin(), rest.end(), '<')));
}

TEST(WeekPlotTest, SvgHasOnePolylinePointPerSampleAndTheObservations) {
  const TimeSeriesPlot plot = DailyWave();
  const std::string svg = RenderSvg(plot);
  ExpectBalancedTags(svg);
  std::smatch match;
  ASSERT_TRUE(std::regex_search(svg, match, std::regex(R"re(<polyline class="probability"[^>]*points="([^"]*)")re")));
  std::istringstream points(match[1].str());
  std::string point;
  size_t count = 0;
  while (points >> point) {
    ++count;
    EXPECT_TRUE(std::regex_match(point, std::regex(R"(-?[0-9.]+,-?[0-9.]+)"))) << point;
  }
  EXPECT_EQ(count, plot.probability.size());
  const std::regex circle("<circle class=\"observation\"");
  EXPECT_EQ(std::distance(std::sregex_iterator(svg.begin(), svg.end(), circle), std::sregex_iterator()), 28);
  EXPECT_NE(svg.find("door &lt;open&gt;"), std::string::npos);
  EXPECT_NE(svg.find("class=\"last-observation\""), std::string::npos);
  EXPECT_NE(svg.find(">day 6<"), std::string::npos);
}

TEST(WeekPlotTest, RasterDrawsTheCurveAndTheObservationsWhereTheyAre) {
  const TimeSeriesPlot plot = DailyWave();
  const PlotLayout layout;
  const Image image = RenderRaster(plot, layout);
  ASSERT_EQ(image.channels, 3);
  ASSERT_EQ(image.width, layout.width);
  const auto is = [&](int x, int y, Rgb c) {
    return image.at(x, y, 0) == c.r && image.at(x, y, 1) == c.g && image.at(x, y, 2) == c.b;
  };
  // The curve is drawn last: every sample's pixel is the curve's colour.
  for (const PlotPoint& p : plot.probability) {
    const int x = static_cast<int>(std::lround(layout.X(plot, p.t)));
    const int y = static_cast<int>(std::lround(layout.Y(p.value)));
    if (x >= image.width) continue;  // the sample at `end` lies on the frame's right edge
    EXPECT_TRUE(is(x, y, kCurveColor)) << x << "," << y;
  }
  // An observation far from the curve (p ≈ 0.5 at hour 6k + 0.5 is far from 0 and 1) is red.
  const PlotPoint& o = plot.observations[0];
  EXPECT_TRUE(is(static_cast<int>(std::lround(layout.X(plot, o.t))), static_cast<int>(std::lround(layout.Y(o.value))),
                 kObservationColor));
  // Outside the plot area stays white.
  EXPECT_TRUE(is(2, 2, {255, 255, 255}));
  size_t curve_pixels = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) curve_pixels += is(x, y, kCurveColor);
  }
  EXPECT_GT(curve_pixels, static_cast<size_t>(layout.width - layout.left - layout.right));
}

}  // namespace
}  // namespace fremen::formats
