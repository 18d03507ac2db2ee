#include "bench_page.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

#include "core/error.h"
#include "report_data.h"

namespace fs = std::filesystem;

namespace idyvins::app {

namespace {

std::string escapeHtml(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '&')
      out += "&amp;";
    else if (c == '"')
      out += "&quot;";
    else
      out += c;
  }
  return out;
}

/// bench's markdown (pipe tables, paragraphs, **bold**) as HTML.
std::string markdownHtml(const std::string& md) {
  std::ostringstream html;
  std::istringstream in(md);
  std::string line;
  bool in_table = false;
  const auto cells = [](const std::string& row, const char* tag) {
    std::string out = "<tr>", cell;
    std::istringstream ss(row.substr(1));
    while (std::getline(ss, cell, '|')) {
      const std::size_t a = cell.find_first_not_of(' '), b = cell.find_last_not_of(' ');
      std::string text = escapeHtml(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
      for (std::size_t at; (at = text.find("**")) != std::string::npos;) {
        const std::size_t end = text.find("**", at + 2);
        if (end == std::string::npos) break;
        text = text.substr(0, at) + "<b>" + text.substr(at + 2, end - at - 2) + "</b>" + text.substr(end + 2);
      }
      out += std::string("<") + tag + ">" + text + "</" + tag + ">";
    }
    return out + "</tr>\n";
  };
  bool header = true;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '|') {
      if (line.rfind("| ---", 0) == 0) continue;
      if (!in_table) html << "<table>\n", header = true;
      in_table = true;
      html << cells(line, header ? "th" : "td");
      header = false;
      continue;
    }
    if (in_table) html << "</table>\n";
    in_table = false;
    if (!line.empty()) html << "<p>" << escapeHtml(line) << "</p>\n";
  }
  if (in_table) html << "</table>\n";
  return html.str();
}

std::string base64(const std::string& bytes) {
  static const char* const abc = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += {abc[v >> 18], abc[(v >> 12) & 63], abc[(v >> 6) & 63], abc[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    out += {abc[v >> 18], abc[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8);
    out += {abc[v >> 18], abc[(v >> 12) & 63], abc[(v >> 6) & 63], '='};
  }
  return out;
}

/// One page per sequence: its finished runs side by side. Returns sequence -> link or why none.
std::map<std::string, std::string> sequencePages(const fs::path& out, const Sweep& sweep,
                                                 const std::vector<JobResult>& found) {
  std::map<std::string, std::vector<std::string>> folders;
  for (std::size_t k = 0; k < found.size(); ++k)
    if (found[k].problem.empty()) folders[sweep.jobs[k].sequence].push_back(found[k].folder);
  std::map<std::string, std::string> links;
  fs::create_directories(out / "pages");
  for (const auto& [sequence, runs] : folders) {
    try {
      const std::string page = reportHtml(reportData(runs, ReportOptions{}));
      std::ofstream(out / "pages" / (sequence + ".html"), std::ios::binary) << page;
      links[sequence] = "<a href=\"pages/" + escapeHtml(sequence) + ".html\">" + escapeHtml(sequence) + "</a>";
    } catch (const std::exception& e) {
      links[sequence] = escapeHtml(sequence) + ": no page (" + escapeHtml(e.what()) + ")";
    }
  }
  return links;
}

}  // namespace

void writeBenchPages(const fs::path& out, const Sweep& sweep, const std::vector<JobResult>& found,
                     const std::vector<std::string>& tables) {
  std::ostringstream html;
  html << "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>idyvins bench: "
       << escapeHtml(sweep.suite) << "</title><style>" << reportStyle()
       << "</style></head><body><main>\n<h1>idyvins bench: suite " << escapeHtml(sweep.suite)
       << "</h1>\n<p class=\"note\">modes " << sweep.modes.size() << ", jobs " << sweep.jobs.size() << ", commit "
       << escapeHtml(sweep.commit) << "; each sequence's page shows its runs side by side.</p>\n";
  static const char* const titles[] = {"Table I: accuracy", "Table II: time per stage", "Dynamic features"};
  for (std::size_t i = 0; i < tables.size() && i < 3; ++i)
    html << "<h2>" << titles[i] << "</h2>\n" << markdownHtml(tables[i]);
  html << "<h2>Sequences</h2>\n<ul>\n";
  for (const auto& [sequence, link] : sequencePages(out, sweep, found)) html << "<li>" << link << "</li>\n";
  html << "</ul>\n";
  if (fs::is_directory(out / "plots")) {
    html << "<h2>Plots</h2>\n";
    std::vector<fs::path> pngs;
    for (const auto& f : fs::directory_iterator(out / "plots"))
      if (f.path().extension() == ".png") pngs.push_back(f.path());
    std::sort(pngs.begin(), pngs.end());
    for (const fs::path& p : pngs) {
      std::ifstream in(p, std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(in)), {});
      html << "<figure class=\"chart\"><figcaption>" << escapeHtml(p.filename().string())
           << "</figcaption><img style=\"max-width:100%\" src=\"data:image/png;base64," << base64(bytes)
           << "\"></figure>\n";
    }
  }
  html << "</main></body></html>\n";
  std::ofstream page(out / "report.html", std::ios::binary);
  page << html.str();
  if (!page) throw InputError((out / "report.html").string(), "write failed");
}

}  // namespace idyvins::app
