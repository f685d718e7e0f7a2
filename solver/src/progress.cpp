// Progress report of a run. See rubble/io/progress.hpp.
#include "rubble/io/progress.hpp"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace rubble {
namespace {

constexpr double kRedrawInterval = 0.1;  // s between bar redraws
constexpr double kPlainInterval = 30.0;  // s between plain lines at the latest
constexpr int kBarWidth = 8;

// Wall time as "M:SS" below an hour, else "H:MM:SS"; "--:--" when unknown.
std::string clock_text(double s) {
  if (!std::isfinite(s) || s < 0) return "--:--";
  const long long total = static_cast<long long>(s + 0.5);
  char buf[32];
  if (total < 3600) std::snprintf(buf, sizeof buf, "%lld:%02lld", total / 60, total % 60);
  else std::snprintf(buf, sizeof buf, "%lld:%02lld:%02lld", total / 3600, (total / 60) % 60, total % 60);
  return buf;
}

int terminal_columns(std::FILE* f) {
  winsize ws{};
  if (ioctl(fileno(f), TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0) return ws.ws_col;
  return 80;
}

}  // namespace

Progress::Progress(double t_end, bool enabled)
    : Progress(t_end, enabled, stderr, isatty(fileno(stderr)) != 0) {}

Progress::Progress(double t_end, bool enabled, std::FILE* out, bool terminal)
    : t_end_(t_end), enabled_(enabled && out != nullptr), out_(out), terminal_(terminal) {}

Progress::~Progress() {
  // Leave the terminal on a fresh line if the run stopped early (exception).
  if (enabled_ && terminal_ && bar_drawn_ && !finished_) {
    std::fputc('\n', out_);
    std::fflush(out_);
  }
}

double Progress::elapsed_s(Clock::time_point now) const {
  return std::chrono::duration<double>(now - wall0_).count();
}

double Progress::eta_s(Clock::time_point now) const {
  const double done = t_ - t0_, wall = elapsed_s(now);
  if (done <= 0 || wall <= 0) return -1;
  return std::max(0.0, t_end_ - t_) * wall / done;
}

void Progress::update(double t, double dt, std::int64_t step) {
  if (!enabled_ || finished_) return;
  const Clock::time_point now = Clock::now();
  t_ = t;
  dt_ = dt;
  step_ = step;
  if (!started_) {  // the first call starts the clocks and reports at once
    started_ = true;
    t0_ = t;
    wall0_ = now;
    const double frac = t_end_ > 0 ? t / t_end_ : 0;
    next_mark_ = (std::floor(frac * 10 + 1e-9) + 1) / 10;
    if (terminal_) draw_bar(now);
    else print_line(now, "");
    last_print_ = now;
    return;
  }
  const double since = std::chrono::duration<double>(now - last_print_).count();
  if (terminal_) {
    if (since >= kRedrawInterval) {
      draw_bar(now);
      last_print_ = now;
    }
    return;
  }
  const double frac = t_end_ > 0 ? t / t_end_ : 0;
  if (frac >= next_mark_ - 1e-12 || since >= kPlainInterval) {
    print_line(now, "");
    last_print_ = now;
    while (next_mark_ <= frac + 1e-12) next_mark_ += 0.1;
  }
}

void Progress::finish() {
  if (!enabled_ || finished_) return;
  finished_ = true;
  if (!started_) return;
  const Clock::time_point now = Clock::now();
  if (terminal_) {
    draw_bar(now);
    std::fputc('\n', out_);
    std::fflush(out_);
  } else {
    print_line(now, "done: ");
  }
}

void Progress::draw_bar(Clock::time_point now) {
  const double frac = t_end_ > 0 ? std::clamp(t_ / t_end_, 0.0, 1.0) : 0;
  const int filled = static_cast<int>(frac * kBarWidth + 0.5);
  char buf[5][64];
  std::snprintf(buf[0], sizeof buf[0], "%.1f%%", 100 * frac);
  std::snprintf(buf[1], sizeof buf[1], "t %.3e/%.3g s", t_, t_end_);
  std::snprintf(buf[2], sizeof buf[2], "dt %.2e s", dt_);
  std::snprintf(buf[3], sizeof buf[3], "step %lld", static_cast<long long>(step_));
  std::snprintf(buf[4], sizeof buf[4], "ETA %s", clock_text(eta_s(now)).c_str());
  // Parts in display order; on a narrow terminal the highest `drop` goes
  // first, because a wrapped line cannot be redrawn in place.
  struct Part {
    std::string text;
    int drop;
  };
  std::vector<Part> parts = {{"[" + std::string(filled, '#') + std::string(kBarWidth - filled, '.') + "]", 2},
                             {buf[0], 0},
                             {buf[1], 0},
                             {buf[2], 3},
                             {buf[3], 1},
                             {clock_text(elapsed_s(now)), 4},
                             {buf[4], 0}};
  const std::size_t width = static_cast<std::size_t>(std::max(terminal_columns(out_) - 1, 10));
  auto join = [&] {
    std::string line;
    for (const auto& p : parts) line += (line.empty() ? "" : " ") + p.text;
    return line;
  };
  std::string line = join();
  while (line.size() > width) {
    auto worst = std::max_element(parts.begin(), parts.end(),
                                  [](const Part& a, const Part& b) { return a.drop < b.drop; });
    if (worst->drop == 0) break;
    parts.erase(worst);
    line = join();
  }
  if (line.size() > width) line.resize(width);
  std::fprintf(out_, "\r%s\x1b[K", line.c_str());
  std::fflush(out_);
  bar_drawn_ = true;
}

void Progress::print_line(Clock::time_point now, const char* prefix) {
  const double frac = t_end_ > 0 ? t_ / t_end_ : 0;
  std::fprintf(out_, "%s%5.1f%%  t = %.6e s of %.6g s  dt = %.3e s  step %lld  elapsed %s  ETA %s\n", prefix,
               100 * frac, t_, t_end_, dt_, static_cast<long long>(step_), clock_text(elapsed_s(now)).c_str(),
               clock_text(eta_s(now)).c_str());
  std::fflush(out_);
}

}  // namespace rubble
