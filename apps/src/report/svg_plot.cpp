#include "report/svg_plot.hpp"

#include "io/text_format.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace fgcal::apps::svg {

using fgcal::apps::detail::xmlEscape;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Figure layout, pixels.
constexpr double kLeft = 64.0, kRight = 18.0, kBottom = 46.0, kTitleHeight = 26.0, kLegendRow = 18.0;
constexpr double kCharWidth = 6.6;  // of the 12 px legend font, for wrapping

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

struct Extent {
  double lo = kInf, hi = -kInf;
  void add(double v) {
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  bool empty() const { return !(lo <= hi); }
};

bool isMark(Series::Kind k) { return k == Series::Kind::Points || k == Series::Kind::Crosses; }

std::size_t stride(const Plot& p, const Series& s) {
  if (!isMark(s.kind) || p.max_points == 0 || s.x.size() <= p.max_points) return 1;
  return (s.x.size() + p.max_points - 1) / p.max_points;
}

/// One legend row per line, wrapped to the figure width.
std::vector<std::vector<const Series*>> legendRows(const Plot& p) {
  std::vector<std::vector<const Series*>> rows;
  double x = kLeft, limit = p.width - kRight;
  for (const Series& s : p.series) {
    if (s.label.empty()) continue;
    const double w = 22.0 + kCharWidth * static_cast<double>(s.label.size()) + 14.0;
    if (rows.empty() || (x + w > limit && !rows.back().empty())) {
      rows.emplace_back();
      x = kLeft;
    }
    rows.back().push_back(&s);
    x += w;
  }
  return rows;
}

double topMargin(const Plot& p) { return kTitleHeight + kLegendRow * static_cast<double>(legendRows(p).size()) + 8.0; }

}  // namespace

double niceStep(double lo, double hi, int target) {
  const double span = hi - lo;
  if (!(span > 0.0) || !std::isfinite(span)) return 1.0;
  const double raw = span / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag;
  const double nice = f < 1.5 ? 1.0 : f < 3.5 ? 2.0 : f < 7.5 ? 5.0 : 10.0;
  return nice * mag;
}

std::vector<double> niceTicks(double lo, double hi, int target) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) return {};
  if (hi < lo) std::swap(lo, hi);
  if (hi == lo) return {lo};
  const double step = niceStep(lo, hi, target);
  // step = m * 10^e with m in {1, 2, 5, 10}: k * m / 10^-e rounds to the
  // decimal the label shows (0.6, not 0.6000000000000001).
  const int e = static_cast<int>(std::floor(std::log10(step) + 1e-9));
  const double m = std::round(step / std::pow(10.0, e));
  auto tick = [&](double k) { return e >= 0 ? k * m * std::pow(10.0, e) : k * m / std::pow(10.0, -e); };
  std::vector<double> ticks;
  const double eps = 1e-9 * step;
  for (double k = std::ceil((lo - eps) / step); tick(k) <= hi + eps; k += 1.0) {
    double t = tick(k);
    if (std::abs(t) < eps) t = 0.0;
    ticks.push_back(t);
  }
  return ticks;
}

std::string formatNumber(double v, double step) {
  if (!std::isfinite(v)) return "";
  if (step > 0.0 && std::abs(v) < 1e-6 * step) v = 0.0;  // rounding noise around a zero tick
  const double a = std::abs(v);
  char buf[40];
  if (a != 0.0 && (a >= 1e6 || a < 1e-4)) {
    // 1e6, 2.5e-7: no '+', no leading zeros in the exponent.
    std::snprintf(buf, sizeof buf, "%.3g", v);
    std::string t = buf;
    const auto e = t.find('e');
    if (e != std::string::npos) {
      std::string mant = t.substr(0, e), ex = t.substr(e + 1);
      const bool neg = !ex.empty() && ex[0] == '-';
      if (!ex.empty() && (ex[0] == '-' || ex[0] == '+')) ex.erase(0, 1);
      ex.erase(0, std::min(ex.find_first_not_of('0'), ex.size() - 1));
      t = mant + "e" + (neg ? "-" : "") + ex;
    }
    return t;
  } else {
    int decimals = 0;
    if (step > 0.0 && std::isfinite(step)) {
      // Enough decimals that consecutive ticks differ (0.25 needs 2, 0.5 needs 1).
      while (decimals < 8 && std::abs(step * std::pow(10.0, decimals) - std::round(step * std::pow(10.0, decimals))) >
                                 1e-6 * step * std::pow(10.0, decimals))
        ++decimals;
    }
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  }
  std::string s = buf;
  if (s.find_first_not_of("-0.") == std::string::npos && s[0] == '-') s.erase(0, 1);  // no "-0"
  return s;
}

Plot::Ranges Plot::ranges() const {
  Extent ex, ey;
  bool bars = false;
  for (const Series& s : series) {
    const std::size_t n = std::min(s.x.size(), s.y.size());
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      if (log_y && !(s.y[i] > 0.0)) continue;
      if (s.kind == Series::Kind::Bars) {
        bars = true;
        ex.add(s.x[i] - 0.5 * s.bar_width);
        ex.add(s.x[i] + 0.5 * s.bar_width);
      } else {
        ex.add(s.x[i]);
      }
      ey.add(log_y ? std::log10(s.y[i]) : s.y[i]);
    }
  }
  for (const Label& l : labels) {
    ex.add(l.x);
    ey.add(log_y ? (l.y > 0 ? std::log10(l.y) : std::nan("")) : l.y);
  }
  if (bars && !log_y) ey.add(0.0);

  auto finish = [](Extent e, std::optional<double> fixed_lo, std::optional<double> fixed_hi, bool log,
                   bool keep_zero) {
    if (e.empty()) {
      e.lo = log ? 0.0 : 0.0;
      e.hi = 1.0;
    }
    if (e.hi == e.lo) {
      const double d = e.lo == 0.0 ? 0.5 : 0.1 * std::abs(e.lo);
      e.lo -= d;
      e.hi += d;
    }
    if (log) {
      e.lo = std::floor(e.lo);
      e.hi = std::ceil(e.hi);
      if (e.hi == e.lo) e.hi += 1.0;
    } else {
      const double pad = 0.04 * (e.hi - e.lo);
      const double lo0 = e.lo;
      e.lo -= pad;
      e.hi += pad;
      if (keep_zero && lo0 >= 0.0 && e.lo < 0.0) e.lo = 0.0;
      const double step = niceStep(e.lo, e.hi);
      e.lo = std::floor(e.lo / step + 1e-9) * step;
      e.hi = std::ceil(e.hi / step - 1e-9) * step;
    }
    auto conv = [&](double v) { return log ? std::log10(v) : v; };
    if (fixed_lo) e.lo = conv(*fixed_lo);
    if (fixed_hi) e.hi = conv(*fixed_hi);
    if (!(e.hi > e.lo)) e.hi = e.lo + 1.0;
    return e;
  };
  const Extent fx = finish(ex, x_min, x_max, false, false);
  const Extent fy = finish(ey, y_min, y_max, log_y, bars);
  Ranges r{fx.lo, fx.hi, fy.lo, fy.hi};
  if (equal_aspect && !log_y) {
    const double pw = width - kLeft - kRight, ph = height - topMargin(*this) - kBottom;
    const double s = std::max((r.x_hi - r.x_lo) / pw, (r.y_hi - r.y_lo) / ph);
    const double cx = 0.5 * (r.x_lo + r.x_hi), cy = 0.5 * (r.y_lo + r.y_hi);
    r = {cx - 0.5 * s * pw, cx + 0.5 * s * pw, cy - 0.5 * s * ph, cy + 0.5 * s * ph};
  }
  return r;
}

namespace {

/// Where data land in the figure.
struct Frame {
  Plot::Ranges r;
  double top = 0.0, pw = 0.0, ph = 0.0;  ///< plot area: top edge, width, height (pixels)
  bool log_y = false;
  bool y_down = false;
  double X(double x) const { return kLeft + (x - r.x_lo) / (r.x_hi - r.x_lo) * pw; }
  /// A data value on the y axis (log10 taken on a log axis).
  double Y(double y) const { return Yaxis(log_y ? std::log10(y) : y); }
  /// An axis value (already log10 on a log axis).
  double Yaxis(double v) const {
    const double along = (v - r.y_lo) / (r.y_hi - r.y_lo) * ph;
    return y_down ? top + along : top + ph - along;
  }
  bool ok(const Series& s, std::size_t i) const {
    return std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && (!log_y || s.y[i] > 0.0);
  }
};

/// The opening <svg>, the title (saying when points were thinned) and the plot area's clip path.
void renderHead(std::ostringstream& o, const Plot& p, const Frame& f, bool standalone) {
  const std::string eid = xmlEscape(p.id);
  std::size_t thinned = 1;
  for (const Series& s : p.series) thinned = std::max(thinned, stride(p, s));
  o << "<svg" << (standalone ? " xmlns=\"http://www.w3.org/2000/svg\"" : "") << " id=\"" << eid << "\" class=\"plot\""
    << " width=\"" << p.width << "\" height=\"" << p.height << "\" viewBox=\"0 0 " << p.width << " " << p.height
    << "\" role=\"img\" aria-label=\"" << xmlEscape(p.title) << "\" font-family=\"sans-serif\">\n";
  o << "<title>" << xmlEscape(p.title) << "</title>\n";
  o << "<rect width=\"" << p.width << "\" height=\"" << p.height << "\" fill=\"#fff\"/>\n";
  o << "<defs><clipPath id=\"" << eid << "-clip\"><rect x=\"" << num(kLeft) << "\" y=\"" << num(f.top)
    << "\" width=\"" << num(f.pw) << "\" height=\"" << num(f.ph) << "\"/></clipPath></defs>\n";
  std::string shown_title = p.title;
  if (thinned > 1) shown_title += " (1 point in " + std::to_string(thinned) + " shown)";
  o << "<text class=\"title\" x=\"" << num(kLeft) << "\" y=\"18\" font-size=\"14\" font-weight=\"bold\" fill=\"#222\">"
    << xmlEscape(shown_title) << "</text>\n";
}

/// Tick positions and the step their labels are formatted with.
struct Ticks {
  std::vector<double> x, y;
  double x_step = 1.0, y_step = 1.0;
};
Ticks ticksOf(const Plot& p, const Frame& f) {
  Ticks t;
  t.x = niceTicks(f.r.x_lo, f.r.x_hi, std::max(3, static_cast<int>(f.pw / 90.0)));
  if (p.integer_x)
    t.x.erase(std::remove_if(t.x.begin(), t.x.end(), [](double v) { return v != std::round(v); }), t.x.end());
  t.x_step = t.x.size() > 1 ? t.x[1] - t.x[0] : 1.0;
  if (p.log_y) {
    const int lo = static_cast<int>(std::ceil(f.r.y_lo - 1e-9)), hi = static_cast<int>(std::floor(f.r.y_hi + 1e-9));
    const int every = std::max(1, (hi - lo + 1 + 6) / 7);
    for (int d = lo; d <= hi; d += every) t.y.push_back(d);
  } else {
    t.y = niceTicks(f.r.y_lo, f.r.y_hi, std::max(3, static_cast<int>(f.ph / 50.0)));
    t.y_step = t.y.size() > 1 ? t.y[1] - t.y[0] : 1.0;
  }
  return t;
}

/// Grid, ticks, tick labels and axis labels.
void renderAxes(std::ostringstream& o, const Plot& p, const Frame& f) {
  const Ticks t = ticksOf(p, f);
  o << "<g class=\"grid\" stroke=\"#e6e6e6\" stroke-width=\"1\">\n";
  for (double v : t.x)
    o << "<line x1=\"" << num(f.X(v)) << "\" y1=\"" << num(f.top) << "\" x2=\"" << num(f.X(v)) << "\" y2=\""
      << num(f.top + f.ph) << "\"/>\n";
  for (double v : t.y)
    o << "<line x1=\"" << num(kLeft) << "\" y1=\"" << num(f.Yaxis(v)) << "\" x2=\"" << num(kLeft + f.pw) << "\" y2=\""
      << num(f.Yaxis(v)) << "\"/>\n";
  o << "</g>\n<g class=\"ticks\" font-size=\"11\" fill=\"#444\">\n";
  for (double v : t.x)
    o << "<text x=\"" << num(f.X(v)) << "\" y=\"" << num(f.top + f.ph + 15) << "\" text-anchor=\"middle\">"
      << xmlEscape(formatNumber(v, t.x_step)) << "</text>\n";
  for (double v : t.y) {
    const std::string label = p.log_y ? formatNumber(std::pow(10.0, v), std::pow(10.0, v)) : formatNumber(v, t.y_step);
    o << "<text x=\"" << num(kLeft - 6) << "\" y=\"" << num(f.Yaxis(v) + 4) << "\" text-anchor=\"end\">"
      << xmlEscape(label) << "</text>\n";
  }
  o << "</g>\n";
  o << "<text class=\"xlabel\" x=\"" << num(kLeft + f.pw / 2) << "\" y=\"" << num(p.height - 8.0)
    << "\" text-anchor=\"middle\" font-size=\"12\" fill=\"#222\">" << xmlEscape(p.x_label) << "</text>\n";
  o << "<text class=\"ylabel\" transform=\"translate(14 " << num(f.top + f.ph / 2)
    << ") rotate(-90)\" text-anchor=\"middle\" font-size=\"12\" fill=\"#222\">" << xmlEscape(p.y_label) << "</text>\n";
}

void renderPoints(std::ostringstream& o, const Plot& p, const Frame& f, const Series& s) {
  const std::size_t n = std::min(s.x.size(), s.y.size());
  o << "<g fill=\"" << xmlEscape(s.color) << "\" fill-opacity=\"" << s.opacity << "\">";
  for (std::size_t i = 0; i < n; i += stride(p, s))
    if (f.ok(s, i)) o << "<circle cx=\"" << num(f.X(s.x[i])) << "\" cy=\"" << num(f.Y(s.y[i])) << "\" r=\"" << s.size << "\"/>";
  o << "</g>\n";
}

void renderCrosses(std::ostringstream& o, const Plot& p, const Frame& f, const Series& s) {
  const std::size_t n = std::min(s.x.size(), s.y.size());
  o << "<path fill=\"none\" stroke=\"" << xmlEscape(s.color) << "\" stroke-opacity=\"" << s.opacity
    << "\" stroke-width=\"1.3\" d=\"";
  for (std::size_t i = 0; i < n; i += stride(p, s))
    if (f.ok(s, i))
      o << "M" << num(f.X(s.x[i]) - s.size) << " " << num(f.Y(s.y[i])) << "h" << num(2 * s.size) << "M"
        << num(f.X(s.x[i])) << " " << num(f.Y(s.y[i]) - s.size) << "v" << num(2 * s.size);
  o << "\"/>\n";
}

/// A polyline; a point that cannot be drawn lifts the pen.
void renderLine(std::ostringstream& o, const Frame& f, const Series& s) {
  const std::size_t n = std::min(s.x.size(), s.y.size());
  o << "<path fill=\"none\" stroke=\"" << xmlEscape(s.color) << "\" stroke-opacity=\"" << s.opacity
    << "\" stroke-width=\"" << s.size << "\" stroke-linejoin=\"round\"";
  if (!s.dash.empty()) o << " stroke-dasharray=\"" << xmlEscape(s.dash) << "\"";
  o << " d=\"";
  bool pen_down = false;
  for (std::size_t i = 0; i < n; ++i) {
    if (!f.ok(s, i)) {
      pen_down = false;
      continue;
    }
    o << (pen_down ? "L" : "M") << num(f.X(s.x[i])) << " " << num(f.Y(s.y[i]));
    pen_down = true;
  }
  o << "\"/>\n";
}

void renderBars(std::ostringstream& o, const Frame& f, const Series& s) {
  const std::size_t n = std::min(s.x.size(), s.y.size());
  const double base = f.log_y ? f.top + f.ph : std::clamp(f.Y(0.0), f.top, f.top + f.ph);
  o << "<g fill=\"" << xmlEscape(s.color) << "\" fill-opacity=\"" << s.opacity << "\">";
  for (std::size_t i = 0; i < n; ++i) {
    if (!f.ok(s, i)) continue;
    const double x0 = f.X(s.x[i] - 0.5 * s.bar_width), x1 = f.X(s.x[i] + 0.5 * s.bar_width);
    const double y = f.Y(s.y[i]);
    o << "<rect x=\"" << num(x0) << "\" y=\"" << num(std::min(y, base)) << "\" width=\""
      << num(std::max(0.0, x1 - x0 - 1.0)) << "\" height=\"" << num(std::abs(base - y)) << "\"/>";
  }
  o << "</g>\n";
}

/// Series and labels clipped to the plot area; "no data" when nothing can be
/// drawn; the plot area's frame.
void renderData(std::ostringstream& o, const Plot& p, const Frame& f) {
  bool any = false;
  o << "<g clip-path=\"url(#" << xmlEscape(p.id) << "-clip)\">\n";
  for (const Series& s : p.series) {
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) any = any || f.ok(s, i);
    switch (s.kind) {
      case Series::Kind::Points: renderPoints(o, p, f, s); break;
      case Series::Kind::Crosses: renderCrosses(o, p, f, s); break;
      case Series::Kind::Line: renderLine(o, f, s); break;
      case Series::Kind::Bars: renderBars(o, f, s); break;
    }
  }
  for (const Label& l : p.labels)
    o << "<text x=\"" << num(f.X(l.x) + l.dx) << "\" y=\"" << num(f.Y(l.y) + l.dy) << "\" font-size=\"11\" fill=\""
      << xmlEscape(l.color) << "\">" << xmlEscape(l.text) << "</text>\n";
  o << "</g>\n";
  if (!any)
    o << "<text x=\"" << num(kLeft + f.pw / 2) << "\" y=\"" << num(f.top + f.ph / 2)
      << "\" text-anchor=\"middle\" font-size=\"13\" fill=\"#888\">" << xmlEscape(p.empty_text) << "</text>\n";
  o << "<rect x=\"" << num(kLeft) << "\" y=\"" << num(f.top) << "\" width=\"" << num(f.pw) << "\" height=\"" << num(f.ph)
    << "\" fill=\"none\" stroke=\"#888\"/>\n";
}

/// A legend entry's mark at (x, y).
void renderLegendMark(std::ostringstream& o, const Series& s, double x, double y) {
  const std::string color = xmlEscape(s.color);
  switch (s.kind) {
    case Series::Kind::Points:
      o << "<circle cx=\"" << num(x + 8) << "\" cy=\"" << num(y - 4) << "\" r=\"4\" fill=\"" << color << "\"/>";
      break;
    case Series::Kind::Crosses:
      o << "<path d=\"M" << num(x + 3) << " " << num(y - 4) << "h10M" << num(x + 8) << " " << num(y - 9)
        << "v10\" stroke=\"" << color << "\" stroke-width=\"1.5\"/>";
      break;
    case Series::Kind::Line:
      o << "<line x1=\"" << num(x) << "\" y1=\"" << num(y - 4) << "\" x2=\"" << num(x + 16) << "\" y2=\"" << num(y - 4)
        << "\" stroke=\"" << color << "\" stroke-width=\"" << std::max(1.5, s.size) << "\""
        << (s.dash.empty() ? std::string() : " stroke-dasharray=\"" + xmlEscape(s.dash) + "\"") << "/>";
      break;
    case Series::Kind::Bars:
      o << "<rect x=\"" << num(x + 2) << "\" y=\"" << num(y - 10) << "\" width=\"12\" height=\"12\" fill=\"" << color
        << "\"/>";
      break;
  }
}

/// Legend rows under the title.
void renderLegend(std::ostringstream& o, const Plot& p) {
  const auto rows = legendRows(p);
  o << "<g class=\"legend\" font-size=\"12\" fill=\"#222\">\n";
  for (std::size_t row = 0; row < rows.size(); ++row) {
    double x = kLeft;
    const double y = kTitleHeight + kLegendRow * static_cast<double>(row) + 10.0;
    for (const Series* s : rows[row]) {
      renderLegendMark(o, *s, x, y);
      o << "<text x=\"" << num(x + 22) << "\" y=\"" << num(y) << "\">" << xmlEscape(s->label) << "</text>\n";
      x += 22.0 + kCharWidth * static_cast<double>(s->label.size()) + 14.0;
    }
  }
  o << "</g>\n";
}

}  // namespace

std::string Plot::render(bool standalone) const {
  Frame f;
  f.r = ranges();
  f.top = topMargin(*this);
  f.pw = width - kLeft - kRight;
  f.ph = height - f.top - kBottom;
  f.log_y = log_y;
  f.y_down = y_down;
  std::ostringstream o;
  renderHead(o, *this, f, standalone);
  renderAxes(o, *this, f);
  renderData(o, *this, f);
  renderLegend(o, *this);
  o << "</svg>\n";
  return o.str();
}

Series histogram(const std::vector<double>& values, int bins, double lo, double hi, std::string label,
                 std::string color) {
  Series s;
  s.kind = Series::Kind::Bars;
  s.label = std::move(label);
  s.color = std::move(color);
  bins = std::max(1, bins);
  if (!(hi > lo)) hi = lo + 1.0;
  const double w = (hi - lo) / bins;
  s.bar_width = w;
  std::vector<double> count(static_cast<std::size_t>(bins), 0.0);
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    const int b = std::clamp(static_cast<int>(std::floor((v - lo) / w)), 0, bins - 1);
    count[static_cast<std::size_t>(b)] += 1.0;
  }
  for (int b = 0; b < bins; ++b) {
    s.x.push_back(lo + (b + 0.5) * w);
    s.y.push_back(count[static_cast<std::size_t>(b)]);
  }
  return s;
}

}  // namespace fgcal::apps::svg
