#include "support/chromium_render.hpp"

#include <cstdio>
#include <sstream>
#include <unistd.h>

namespace errfield::test {

namespace fs = std::filesystem;

namespace {
constexpr const char* kChromium = "/usr/bin/chromium";

std::string run(const std::string& cmd) {
  std::string out;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return out;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  ::pclose(p);
  return out;
}
}  // namespace

std::string chromium_unavailable_reason() {
  if (!fs::exists(kChromium)) return "chromium not installed (scripts/setup.sh installs it)";
  if (!fs::exists("/usr/bin/python3")) return "/usr/bin/python3 missing";
  return {};
}

std::size_t count_occurrences(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

RenderResult render_in_chromium(const fs::path& html, const std::vector<std::string>& colors, int width,
                                int height) {
  static int counter = 0;
  const fs::path dir = fs::temp_directory_path() /
                       ("errfield_render_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  fs::create_directories(dir);
  const std::string flags = std::string(kChromium) +
                            " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
                            " --disable-background-networking --disable-component-update --disable-sync"
                            " --user-data-dir=" + (dir / "profile").string();
  const std::string url = "file://" + fs::absolute(html).string();
  RenderResult r;
  r.dom = run("timeout 120 " + flags + " --dump-dom " + url + " 2>/dev/null");
  const fs::path png = dir / "shot.png";
  run("timeout 120 " + flags + " --screenshot=" + png.string() + " --window-size=" + std::to_string(width) + "," +
      std::to_string(height) + " " + url + " >/dev/null 2>&1");
  if (fs::exists(png)) {
    std::string cmd = "/usr/bin/python3 " ERRFIELD_SOURCE_DIR "/tests/peers/png_color_census.py " + png.string();
    for (const auto& c : colors) cmd += " '" + c + "'";
    std::istringstream in(run(cmd));
    in >> r.width >> r.height >> r.distinct_colors;
    std::string color;
    long n = 0;
    while (in >> color >> n) r.pixels[color] = n;
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
  return r;
}

}  // namespace errfield::test
