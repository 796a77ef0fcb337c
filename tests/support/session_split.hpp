#pragma once
// Splitting one SIMULATED session (`errfield simulate --out all.csv`) into training and held-out
// files as a user splits a measured data set: both keep the SIMULATED comment lines, the header and
// the base rows (one session: the same base-point reading), the first n_train targets train.

#include <sstream>
#include <string>

namespace errfield::testing {

struct SessionSplit {
  std::string train, hold;  ///< file texts
  std::size_t targets = 0;  ///< target rows in the session
};

inline SessionSplit split_session(const std::string& csv_text, std::size_t n_train) {
  std::istringstream in(csv_text);
  std::string line, header, comments, base_rows, train_rows, hold_rows;
  SessionSplit out;
  while (std::getline(in, line)) {
    if (line.rfind('#', 0) == 0) comments += line + "\n";
    else if (header.empty()) header = line + "\n";
    else if (line.find(",base,") != std::string::npos) base_rows += line + "\n";
    else (out.targets++ < n_train ? train_rows : hold_rows) += line + "\n";
  }
  out.train = comments + header + base_rows + train_rows;
  out.hold = comments + header + base_rows + hold_rows;
  return out;
}

}  // namespace errfield::testing
