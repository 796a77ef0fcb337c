#pragma once
// Renders an HTML file in headless Chromium (Debian's /usr/bin/chromium) for tests that check a
// report draws: the live DOM after layout, and a screenshot's colour census (tests/peers/
// png_color_census.py, standard-library Python only).

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace errfield::test {

/// Empty when Chromium and /usr/bin/python3 are available; otherwise why the check is skipped.
std::string chromium_unavailable_reason();

struct RenderResult {
  std::string dom;                     ///< --dump-dom output
  int width = 0, height = 0;           ///< screenshot size (px)
  int distinct_colors = 0;             ///< distinct RGB values in the screenshot
  std::map<std::string, long> pixels;  ///< pixels near each requested colour ("#rrggbb")
};

/// Runs Chromium on `html` (a profile in a fresh temporary directory) and counts pixels near
/// `colors` in a width x height screenshot.
RenderResult render_in_chromium(const std::filesystem::path& html, const std::vector<std::string>& colors,
                                int width = 1100, int height = 1400);

/// Occurrences of `what` in `s`.
std::size_t count_occurrences(const std::string& s, const std::string& what);

}  // namespace errfield::test
