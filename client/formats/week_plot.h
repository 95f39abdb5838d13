// A picture of one state over time, like Figs. 1-2 of the FreMEn paper: the predicted probability
// p(t) as a curve, the observations s(t) as dots, and the time of the last observation (before it
// the model reconstructs, after it predicts). Written as SVG (with axes and labels) or rasterised
// to an RGB image for PNG. Pure functions; thread-safe.
#pragma once

#include <string>
#include <vector>

#include "client/formats/gray_image.h"
#include "client/formats/raster.h"

namespace fremen::formats {

struct PlotPoint {
  double t;      // seconds
  double value;  // in [0, 1]
};

struct TimeSeriesPlot {
  std::string title;
  // The time axis [start, end), seconds. REQUIRES: start < end.
  double start = 0;
  double end = 0;
  // p(t), in time order; drawn as one polyline.
  std::vector<PlotPoint> probability;
  // The observations inside [start, end); others are not drawn.
  std::vector<PlotPoint> observations;
  // When inside [start, end): a vertical line marking the last observation.
  double last_observation = -1e300;
};

// Picture size and the plot area inside it, shared by the SVG and the raster so that both show the
// same picture.
struct PlotLayout {
  int width = 960;
  int height = 320;
  int left = 48, right = 16, top = 28, bottom = 36;

  double X(const TimeSeriesPlot& plot, double t) const;
  double Y(double value) const;
};

// An SVG document: a frame, day lines labelled by day number, p(t) as one <polyline> with one
// point per sample, observations as <circle>s, the last-observation marker, and the title.
std::string RenderSvg(const TimeSeriesPlot& plot, const PlotLayout& layout = {});

// The same picture on a white RGB image (no text): frame and day lines gray, observations red
// dots, p(t) a green line, the last-observation marker blue.
Image RenderRaster(const TimeSeriesPlot& plot, const PlotLayout& layout = {});

// The colours of the picture (Fig. 1's: observations red, the model green).
inline constexpr Rgb kCurveColor{0, 150, 0};
inline constexpr Rgb kObservationColor{220, 0, 0};
inline constexpr Rgb kMarkerColor{0, 0, 220};
inline constexpr Rgb kGridColor{200, 200, 200};

}  // namespace fremen::formats
