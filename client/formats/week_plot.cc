// SVG and raster rendering of a p(t) plot (see week_plot.h).
#include "client/formats/week_plot.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace fremen::formats {

namespace {

constexpr double kDay = 86400;

std::string SvgColor(Rgb c) { return absl::StrFormat("rgb(%d,%d,%d)", c.r, c.g, c.b); }

// Escapes text for an SVG text node.
std::string EscapeXml(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

bool Inside(const TimeSeriesPlot& plot, double t) { return t >= plot.start && t < plot.end; }

// The times of the day lines: every whole day since the start, at most 31 of them (a longer span
// gets none rather than a solid gray block).
std::vector<double> DayLines(const TimeSeriesPlot& plot) {
  std::vector<double> lines;
  if ((plot.end - plot.start) / kDay > 31) return lines;
  for (double t = plot.start + kDay; t < plot.end; t += kDay) lines.push_back(t);
  return lines;
}

}  // namespace

double PlotLayout::X(const TimeSeriesPlot& plot, double t) const {
  return left + (t - plot.start) / (plot.end - plot.start) * (width - left - right);
}

double PlotLayout::Y(double value) const { return top + (1.0 - value) * (height - top - bottom); }

std::string RenderSvg(const TimeSeriesPlot& plot, const PlotLayout& l) {
  std::string svg = absl::StrFormat(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" "
      "font-family=\"sans-serif\" font-size=\"11\">\n"
      "<rect x=\"0\" y=\"0\" width=\"%d\" height=\"%d\" fill=\"white\"/>\n",
      l.width, l.height, l.width, l.height, l.width, l.height);
  absl::StrAppend(&svg, "<title>", EscapeXml(plot.title), "</title>\n");
  absl::StrAppend(&svg,
                  absl::StrFormat("<text x=\"%d\" y=\"%d\">%s</text>\n", l.left, l.top - 10, EscapeXml(plot.title)));

  // Frame, the p = 0, 0.5 and 1 levels, and the day lines.
  const double x0 = l.X(plot, plot.start), x1 = l.X(plot, plot.end);
  absl::StrAppend(&svg, absl::StrFormat("<rect class=\"frame\" x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" "
                                        "fill=\"none\" stroke=\"black\"/>\n",
                                        x0, l.Y(1), x1 - x0, l.Y(0) - l.Y(1)));
  for (double level : {0.0, 0.5, 1.0}) {
    absl::StrAppend(&svg, absl::StrFormat("<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%.1f</text>\n", l.left - 4,
                                          l.Y(level) + 4, level));
  }
  int day = 1;
  for (double t : DayLines(plot)) {
    absl::StrAppend(&svg, absl::StrFormat("<line class=\"day\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" "
                                          "stroke=\"%s\"/>\n",
                                          l.X(plot, t), l.Y(1), l.X(plot, t), l.Y(0), SvgColor(kGridColor)));
    absl::StrAppend(&svg, absl::StrFormat("<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">day %d</text>\n",
                                          l.X(plot, t), l.Y(0) + 14, day++));
  }
  absl::StrAppend(&svg, absl::StrFormat("<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">time since %.0f s</text>\n",
                                        (x0 + x1) / 2, l.height - 4, plot.start));

  // Observations under the curve.
  for (const PlotPoint& o : plot.observations) {
    if (!Inside(plot, o.t)) continue;
    absl::StrAppend(&svg,
                    absl::StrFormat("<circle class=\"observation\" cx=\"%.1f\" cy=\"%.1f\" r=\"2\" fill=\"%s\"/>\n",
                                    l.X(plot, o.t), l.Y(o.value), SvgColor(kObservationColor)));
  }
  if (Inside(plot, plot.last_observation)) {
    const double x = l.X(plot, plot.last_observation);
    absl::StrAppend(&svg, absl::StrFormat("<line class=\"last-observation\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" "
                                          "y2=\"%.1f\" stroke=\"%s\" stroke-dasharray=\"4 3\"/>\n",
                                          x, l.Y(1), x, l.Y(0), SvgColor(kMarkerColor)));
  }
  std::string points;
  for (const PlotPoint& p : plot.probability) {
    absl::StrAppend(&points, points.empty() ? "" : " ", absl::StrFormat("%.1f,%.1f", l.X(plot, p.t), l.Y(p.value)));
  }
  absl::StrAppend(&svg, "<polyline class=\"probability\" fill=\"none\" stroke=\"", SvgColor(kCurveColor),
                  "\" stroke-width=\"1.5\" points=\"", points, "\"/>\n");
  absl::StrAppend(&svg, "</svg>\n");
  return svg;
}

Image RenderRaster(const TimeSeriesPlot& plot, const PlotLayout& l) {
  Image image(l.width, l.height, 3, 255);
  const int x0 = static_cast<int>(std::lround(l.X(plot, plot.start)));
  const int x1 = static_cast<int>(std::lround(l.X(plot, plot.end)));
  const int y0 = static_cast<int>(std::lround(l.Y(0))), y1 = static_cast<int>(std::lround(l.Y(1)));
  // Back to front: frame and grid, observations, marker, then the curve over everything.
  DrawLine(image, x0, y0, x1, y0, {0, 0, 0});
  DrawLine(image, x0, y1, x1, y1, {0, 0, 0});
  DrawLine(image, x0, y0, x0, y1, {0, 0, 0});
  DrawLine(image, x1, y0, x1, y1, {0, 0, 0});
  for (double t : DayLines(plot)) {
    const int x = static_cast<int>(std::lround(l.X(plot, t)));
    DrawLine(image, x, y0, x, y1, kGridColor);
  }
  const int y_half = static_cast<int>(std::lround(l.Y(0.5)));
  DrawLine(image, x0, y_half, x1, y_half, kGridColor);
  for (const PlotPoint& o : plot.observations) {
    if (!Inside(plot, o.t)) continue;
    DrawDot(image, static_cast<int>(std::lround(l.X(plot, o.t))), static_cast<int>(std::lround(l.Y(o.value))), 2,
            kObservationColor);
  }
  if (Inside(plot, plot.last_observation)) {
    const int x = static_cast<int>(std::lround(l.X(plot, plot.last_observation)));
    for (int y = y1; y <= y0; y += 7) DrawLine(image, x, y, x, std::min(y + 3, y0), kMarkerColor);
  }
  for (size_t i = 0; i + 1 < plot.probability.size(); ++i) {
    const PlotPoint& a = plot.probability[i];
    const PlotPoint& b = plot.probability[i + 1];
    DrawLine(image, static_cast<int>(std::lround(l.X(plot, a.t))), static_cast<int>(std::lround(l.Y(a.value))),
             static_cast<int>(std::lround(l.X(plot, b.t))), static_cast<int>(std::lround(l.Y(b.value))), kCurveColor);
  }
  if (plot.probability.size() == 1) {
    const PlotPoint& a = plot.probability[0];
    PutPixel(image, static_cast<int>(std::lround(l.X(plot, a.t))), static_cast<int>(std::lround(l.Y(a.value))),
             kCurveColor);
  }
  return image;
}

}  // namespace fremen::formats
