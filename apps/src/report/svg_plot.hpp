// A small plotting helper of our own for the calibration report: scatter,
// line, histogram and free-drawing plots rendered to inline SVG with axes,
// "nice" ticks, labels and a legend. No JavaScript, no external resources:
// the output is a plain <svg> element to paste into an HTML page.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace fgcal::apps::svg {

/// Tick positions at 1-2-5 steps covering [lo, hi] with about `target` ticks;
/// every tick lies inside [lo, hi]. lo == hi gives one tick.
std::vector<double> niceTicks(double lo, double hi, int target = 6);

/// The 1-2-5 step niceTicks uses for [lo, hi].
double niceStep(double lo, double hi, int target = 6);

/// A tick label: as few decimals as the step needs, no "-0".
std::string formatNumber(double v, double step);

struct Series {
  enum class Kind {
    Points,   ///< filled circles of radius `size`
    Crosses,  ///< '+' marks of half-width `size`
    Line,     ///< a polyline of width `size`; a NaN in x or y breaks it
    Bars,     ///< bars from y = 0 (or the bottom of a log axis), centred at x, `bar_width` wide in data units
  };
  std::string label;  ///< legend entry; empty: not in the legend
  std::string color = "#1f77b4";
  Kind kind = Kind::Points;
  std::vector<double> x, y;
  double size = 2.0;
  double opacity = 1.0;
  std::string dash;        ///< Line: stroke-dasharray, e.g. "6 3"
  double bar_width = 0.0;  ///< Bars
};

/// A text placed at data coordinates.
struct Label {
  double x = 0.0, y = 0.0;
  std::string text;
  std::string color = "#222";
  double dx = 4.0, dy = -4.0;  ///< offset in pixels (y down), so that nearby labels can be kept apart
};

struct Plot {
  std::string id;  ///< the <svg id>; reports and tests find plots by it
  std::string title, x_label, y_label;
  int width = 560, height = 380;  ///< pixels, the whole figure
  /// Fixed axis ranges; unset: from the data, padded and widened to ticks.
  std::optional<double> x_min, x_max, y_min, y_max;
  bool equal_aspect = false;  ///< one data unit is as long on both axes (maps of the rig)
  bool log_y = false;         ///< decades on y; values <= 0 are left out
  bool y_down = false;        ///< y grows downward (image coordinates: v from the top row)
  bool integer_x = false;     ///< x ticks at whole numbers only (iterations)
  /// Points and Crosses beyond this many in one series are thinned to every
  /// k-th (the title says so), to keep the page light on large datasets.
  std::size_t max_points = 20000;
  std::vector<Series> series;
  std::vector<Label> labels;
  std::string empty_text = "no data";  ///< shown when no series has a finite point

  Plot& add(Series s) {
    series.push_back(std::move(s));
    return *this;
  }
  /// The figure as an inline <svg> element (no XML declaration, no namespace:
  /// HTML5 knows SVG); `standalone` adds the namespace for an .svg file.
  std::string render(bool standalone = false) const;

  /// The data ranges the axes were given after padding, tick widening and
  /// equal aspect (in log10 units for a log axis); for tests.
  struct Ranges {
    double x_lo, x_hi, y_lo, y_hi;
  };
  Ranges ranges() const;
};

/// Bars counting `values` in `bins` equal bins over [lo, hi] (values outside
/// go to the end bins); an empty `values` gives empty bars.
Series histogram(const std::vector<double>& values, int bins, double lo, double hi, std::string label,
                 std::string color);

}  // namespace fgcal::apps::svg
