#pragma once
// Command-line arguments of a rung, read one at a time: each rung lists its
// options and what they fill, the reading, the values' conversion and the
// messages for a missing value or an unknown argument live here.
//
//   ArgReader r(argc, argv);
//   while (!r.done())
//     if (!(r.value("--scene", a.scene) || r.list("--resolutions", a.resolutions) ||
//           r.flag("--checks", a.checks) || r.append("--set", a.sets)))
//       r.unknown();
//
// Every rung reads its arguments this way, through rung.hpp's RungArgs
// (the options rungs share, and the rung's own in its own_option).
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace rubble::verification {

// "1,2.5,4" -> {1, 2.5, 4}
inline std::vector<double> parse_number_list(const std::string& s) {
  std::vector<double> v;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');) v.push_back(std::stod(item));
  return v;
}

// A --resolutions list must be whole numbers >= `min`, strictly increasing;
// `what` names the unit in the message ("particles over the height").
inline void require_increasing_whole(const std::vector<double>& v, double min, const std::string& what) {
  for (std::size_t i = 0; i < v.size(); ++i)
    if (v[i] < min || v[i] != static_cast<double>(static_cast<long long>(v[i])) || (i > 0 && v[i] <= v[i - 1]))
      throw std::runtime_error("--resolutions: whole numbers of " + what + " (>= " + std::to_string(int(min)) +
                               "), increasing");
}

class ArgReader {
 public:
  // first: the index of the first option (2 after a leading positional word)
  ArgReader(int argc, char** argv, int first = 1) : argc_(argc), argv_(argv), i_(first) {}
  bool done() const { return i_ >= argc_; }

  // Each of these consumes the current argument (and its value) when it is
  // `name`, and says whether it did.
  bool flag(const char* name, bool& out) {
    if (!is(name)) return false;
    out = true;
    ++i_;
    return true;
  }
  bool value(const char* name, std::string& out) {
    if (!is(name)) return false;
    out = take_value();
    return true;
  }
  bool value(const char* name, double& out) {
    if (!is(name)) return false;
    out = std::stod(take_value());
    return true;
  }
  bool value(const char* name, int& out) {
    if (!is(name)) return false;
    out = std::stoi(take_value());
    return true;
  }
  bool append(const char* name, std::vector<std::string>& out) {
    if (!is(name)) return false;
    out.push_back(take_value());
    return true;
  }
  bool list(const char* name, std::vector<double>& out) {
    if (!is(name)) return false;
    out = parse_number_list(take_value());
    return true;
  }
  // "a,b,c" -> {"a", "b", "c"}
  bool words(const char* name, std::vector<std::string>& out) {
    if (!is(name)) return false;
    out.clear();
    std::stringstream ss(take_value());
    for (std::string item; std::getline(ss, item, ',');) out.push_back(item);
    return true;
  }
  [[noreturn]] void unknown() const { throw std::runtime_error("unknown argument " + std::string(argv_[i_])); }

 private:
  bool is(const char* name) const { return std::string(argv_[i_]) == name; }
  std::string take_value() {
    const std::string k = argv_[i_];
    if (i_ + 1 >= argc_) throw std::runtime_error("missing value after " + k);
    i_ += 2;
    return argv_[i_ - 1];
  }
  int argc_;
  char** argv_;
  int i_;
};

}  // namespace rubble::verification
