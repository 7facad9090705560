#include "svg_plot.hpp"

#include "../io/text_format.hpp"

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

std::string Plot::render(bool standalone) const {
  const Ranges r = ranges();
  const double top = topMargin(*this);
  const double pw = width - kLeft - kRight, ph = height - top - kBottom;
  auto X = [&](double x) { return kLeft + (x - r.x_lo) / (r.x_hi - r.x_lo) * pw; };
  auto Y = [&](double y) {
    const double v = log_y ? std::log10(y) : y;
    return top + ph - (v - r.y_lo) / (r.y_hi - r.y_lo) * ph;
  };
  const std::string eid = xmlEscape(id);
  const std::string clip = eid + "-clip";

  std::size_t thinned = 1;
  bool any = false;
  for (const Series& s : series) {
    thinned = std::max(thinned, stride(*this, s));
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && (!log_y || s.y[i] > 0.0)) any = true;
  }

  std::ostringstream o;
  o << "<svg" << (standalone ? " xmlns=\"http://www.w3.org/2000/svg\"" : "") << " id=\"" << eid << "\" class=\"plot\""
    << " width=\"" << width << "\" height=\"" << height << "\" viewBox=\"0 0 " << width << " " << height
    << "\" role=\"img\" aria-label=\"" << xmlEscape(title) << "\" font-family=\"sans-serif\">\n";
  o << "<title>" << xmlEscape(title) << "</title>\n";
  o << "<rect width=\"" << width << "\" height=\"" << height << "\" fill=\"#fff\"/>\n";
  o << "<defs><clipPath id=\"" << clip << "\"><rect x=\"" << num(kLeft) << "\" y=\"" << num(top) << "\" width=\""
    << num(pw) << "\" height=\"" << num(ph) << "\"/></clipPath></defs>\n";
  std::string shown_title = title;
  if (thinned > 1) shown_title += " (1 point in " + std::to_string(thinned) + " shown)";
  o << "<text class=\"title\" x=\"" << num(kLeft) << "\" y=\"18\" font-size=\"14\" font-weight=\"bold\" fill=\"#222\">"
    << xmlEscape(shown_title) << "</text>\n";

  // Grid, ticks and tick labels.
  std::vector<double> xt = niceTicks(r.x_lo, r.x_hi, std::max(3, static_cast<int>(pw / 90.0)));
  if (integer_x)
    xt.erase(std::remove_if(xt.begin(), xt.end(), [](double t) { return t != std::round(t); }), xt.end());
  const double xstep = xt.size() > 1 ? xt[1] - xt[0] : 1.0;
  std::vector<double> yt;
  double ystep = 1.0;
  if (log_y) {
    const int lo = static_cast<int>(std::ceil(r.y_lo - 1e-9)), hi = static_cast<int>(std::floor(r.y_hi + 1e-9));
    const int every = std::max(1, (hi - lo + 1 + 6) / 7);
    for (int d = lo; d <= hi; d += every) yt.push_back(d);
  } else {
    yt = niceTicks(r.y_lo, r.y_hi, std::max(3, static_cast<int>(ph / 50.0)));
    ystep = yt.size() > 1 ? yt[1] - yt[0] : 1.0;
  }
  o << "<g class=\"grid\" stroke=\"#e6e6e6\" stroke-width=\"1\">\n";
  for (double t : xt) o << "<line x1=\"" << num(X(t)) << "\" y1=\"" << num(top) << "\" x2=\"" << num(X(t)) << "\" y2=\"" << num(top + ph) << "\"/>\n";
  for (double t : yt) {
    const double y = top + ph - (t - r.y_lo) / (r.y_hi - r.y_lo) * ph;
    o << "<line x1=\"" << num(kLeft) << "\" y1=\"" << num(y) << "\" x2=\"" << num(kLeft + pw) << "\" y2=\"" << num(y) << "\"/>\n";
  }
  o << "</g>\n<g class=\"ticks\" font-size=\"11\" fill=\"#444\">\n";
  for (double t : xt)
    o << "<text x=\"" << num(X(t)) << "\" y=\"" << num(top + ph + 15) << "\" text-anchor=\"middle\">"
      << xmlEscape(formatNumber(t, xstep)) << "</text>\n";
  for (double t : yt) {
    const double y = top + ph - (t - r.y_lo) / (r.y_hi - r.y_lo) * ph;
    const std::string label = log_y ? formatNumber(std::pow(10.0, t), std::pow(10.0, t)) : formatNumber(t, ystep);
    o << "<text x=\"" << num(kLeft - 6) << "\" y=\"" << num(y + 4) << "\" text-anchor=\"end\">" << xmlEscape(label)
      << "</text>\n";
  }
  o << "</g>\n";
  o << "<text class=\"xlabel\" x=\"" << num(kLeft + pw / 2) << "\" y=\"" << num(height - 8.0)
    << "\" text-anchor=\"middle\" font-size=\"12\" fill=\"#222\">" << xmlEscape(x_label) << "</text>\n";
  o << "<text class=\"ylabel\" transform=\"translate(14 " << num(top + ph / 2)
    << ") rotate(-90)\" text-anchor=\"middle\" font-size=\"12\" fill=\"#222\">" << xmlEscape(y_label) << "</text>\n";

  // Data, clipped to the plot area.
  o << "<g clip-path=\"url(#" << clip << ")\">\n";
  for (const Series& s : series) {
    const std::size_t n = std::min(s.x.size(), s.y.size());
    const std::string color = xmlEscape(s.color);
    auto ok = [&](std::size_t i) {
      return std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && (!log_y || s.y[i] > 0.0);
    };
    switch (s.kind) {
      case Series::Kind::Points: {
        o << "<g fill=\"" << color << "\" fill-opacity=\"" << s.opacity << "\">";
        for (std::size_t i = 0; i < n; i += stride(*this, s))
          if (ok(i)) o << "<circle cx=\"" << num(X(s.x[i])) << "\" cy=\"" << num(Y(s.y[i])) << "\" r=\"" << s.size << "\"/>";
        o << "</g>\n";
        break;
      }
      case Series::Kind::Crosses: {
        o << "<path fill=\"none\" stroke=\"" << color << "\" stroke-opacity=\"" << s.opacity
          << "\" stroke-width=\"1.3\" d=\"";
        for (std::size_t i = 0; i < n; i += stride(*this, s))
          if (ok(i))
            o << "M" << num(X(s.x[i]) - s.size) << " " << num(Y(s.y[i])) << "h" << num(2 * s.size) << "M"
              << num(X(s.x[i])) << " " << num(Y(s.y[i]) - s.size) << "v" << num(2 * s.size);
        o << "\"/>\n";
        break;
      }
      case Series::Kind::Line: {
        o << "<path fill=\"none\" stroke=\"" << color << "\" stroke-opacity=\"" << s.opacity << "\" stroke-width=\""
          << s.size << "\" stroke-linejoin=\"round\"";
        if (!s.dash.empty()) o << " stroke-dasharray=\"" << xmlEscape(s.dash) << "\"";
        o << " d=\"";
        bool pen_down = false;
        for (std::size_t i = 0; i < n; ++i) {
          if (!ok(i)) {
            pen_down = false;
            continue;
          }
          o << (pen_down ? "L" : "M") << num(X(s.x[i])) << " " << num(Y(s.y[i]));
          pen_down = true;
        }
        o << "\"/>\n";
        break;
      }
      case Series::Kind::Bars: {
        const double base = log_y ? top + ph : std::clamp(Y(0.0), top, top + ph);
        o << "<g fill=\"" << color << "\" fill-opacity=\"" << s.opacity << "\">";
        for (std::size_t i = 0; i < n; ++i) {
          if (!ok(i)) continue;
          const double x0 = X(s.x[i] - 0.5 * s.bar_width), x1 = X(s.x[i] + 0.5 * s.bar_width);
          const double y = Y(s.y[i]);
          o << "<rect x=\"" << num(x0) << "\" y=\"" << num(std::min(y, base)) << "\" width=\""
            << num(std::max(0.0, x1 - x0 - 1.0)) << "\" height=\"" << num(std::abs(base - y)) << "\"/>";
        }
        o << "</g>\n";
        break;
      }
    }
  }
  for (const Label& l : labels)
    o << "<text x=\"" << num(X(l.x) + l.dx) << "\" y=\"" << num(Y(l.y) + l.dy) << "\" font-size=\"11\" fill=\""
      << xmlEscape(l.color) << "\">" << xmlEscape(l.text) << "</text>\n";
  o << "</g>\n";
  if (!any)
    o << "<text x=\"" << num(kLeft + pw / 2) << "\" y=\"" << num(top + ph / 2)
      << "\" text-anchor=\"middle\" font-size=\"13\" fill=\"#888\">" << xmlEscape(empty_text) << "</text>\n";
  o << "<rect x=\"" << num(kLeft) << "\" y=\"" << num(top) << "\" width=\"" << num(pw) << "\" height=\"" << num(ph)
    << "\" fill=\"none\" stroke=\"#888\"/>\n";

  // Legend rows under the title.
  const auto rows = legendRows(*this);
  o << "<g class=\"legend\" font-size=\"12\" fill=\"#222\">\n";
  for (std::size_t row = 0; row < rows.size(); ++row) {
    double x = kLeft;
    const double y = kTitleHeight + kLegendRow * static_cast<double>(row) + 10.0;
    for (const Series* s : rows[row]) {
      const std::string color = xmlEscape(s->color);
      switch (s->kind) {
        case Series::Kind::Points:
          o << "<circle cx=\"" << num(x + 8) << "\" cy=\"" << num(y - 4) << "\" r=\"4\" fill=\"" << color << "\"/>";
          break;
        case Series::Kind::Crosses:
          o << "<path d=\"M" << num(x + 3) << " " << num(y - 4) << "h10M" << num(x + 8) << " " << num(y - 9)
            << "v10\" stroke=\"" << color << "\" stroke-width=\"1.5\"/>";
          break;
        case Series::Kind::Line:
          o << "<line x1=\"" << num(x) << "\" y1=\"" << num(y - 4) << "\" x2=\"" << num(x + 16) << "\" y2=\""
            << num(y - 4) << "\" stroke=\"" << color << "\" stroke-width=\"" << std::max(1.5, s->size) << "\""
            << (s->dash.empty() ? std::string() : " stroke-dasharray=\"" + xmlEscape(s->dash) + "\"") << "/>";
          break;
        case Series::Kind::Bars:
          o << "<rect x=\"" << num(x + 2) << "\" y=\"" << num(y - 10) << "\" width=\"12\" height=\"12\" fill=\""
            << color << "\"/>";
          break;
      }
      o << "<text x=\"" << num(x + 22) << "\" y=\"" << num(y) << "\">" << xmlEscape(s->label) << "</text>\n";
      x += 22.0 + kCharWidth * static_cast<double>(s->label.size()) + 14.0;
    }
  }
  o << "</g>\n</svg>\n";
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
