#pragma once
// Progress report of a run on stderr (DESIGN.md, "Command line").
//
// On a terminal: one line redrawn in place, at most ~10 times a second:
//   [###.....] 35.2% t 3.520e-04/0.001 s dt 1.20e-07 s step 2931 0:12 ETA 0:22
// (simulated time / end time, step size, step count, wall time elapsed,
// ETA); on a narrow terminal the elapsed time, dt, bar and step count are
// left out in that order rather than letting the line wrap.
// Not on a terminal (a log file, CI): a plain line every 10 % of simulated
// time, or every 30 s of wall time when steps are slow. The ETA is the
// remaining simulated time over the simulated-time rate seen so far.
// update() is cheap enough to call every step: it reads the clock and
// compares; it formats only when it prints.
#include <chrono>
#include <cstdint>
#include <cstdio>

namespace rubble {

class Progress {
 public:
  // Reports on stderr, as a bar when stderr is a terminal.
  Progress(double t_end, bool enabled);
  // Reports on `out`; `terminal` picks the bar (true) or plain lines.
  Progress(double t_end, bool enabled, std::FILE* out, bool terminal);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void update(double t, double dt, std::int64_t step);
  // Final report (the bar at its last state, then a newline). Idempotent.
  void finish();

 private:
  using Clock = std::chrono::steady_clock;
  void draw_bar(Clock::time_point now);
  void print_line(Clock::time_point now, const char* prefix);
  double elapsed_s(Clock::time_point now) const;
  double eta_s(Clock::time_point now) const;

  double t_end_;
  bool enabled_;
  std::FILE* out_;
  bool terminal_;
  bool started_ = false;
  bool finished_ = false;
  bool bar_drawn_ = false;
  double t0_ = 0;              // simulated time at the first update
  double t_ = 0, dt_ = 0;      // latest state
  std::int64_t step_ = 0;
  Clock::time_point wall0_, last_print_;
  double next_mark_ = 0.1;     // plain mode: next fraction of t_end to report
};

}  // namespace rubble
