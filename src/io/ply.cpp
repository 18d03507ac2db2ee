#include "io/ply.h"

#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

#include "core/error.h"

namespace idyvins::io {

int plyLabel(FeatureLabel label) {
  switch (label) {
    case FeatureLabel::kEliminated:
      return 1;
    case FeatureLabel::kConfirmedDynamic:
      return 2;
    default:
      return 0;
  }
}

void writePly(const std::string& path, const std::vector<LabelledPoint>& points) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!f) throw InputError(path, "cannot write file");
  std::fprintf(f.get(),
               "ply\nformat ascii 1.0\ncomment idyvins map: label 0 static, 1 eliminated dynamic, 2 confirmed dynamic\n"
               "element vertex %zu\nproperty float x\nproperty float y\nproperty float z\nproperty uchar label\n"
               "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
               points.size());
  static const int colors[3][3] = {{170, 170, 170}, {230, 30, 30}, {255, 150, 0}};
  for (const auto& pt : points) {
    const int* c = colors[pt.label < 0 || pt.label > 2 ? 0 : pt.label];
    std::fprintf(f.get(), "%.4f %.4f %.4f %d %d %d %d\n", pt.p.x(), pt.p.y(), pt.p.z(), pt.label, c[0], c[1], c[2]);
  }
  if (std::ferror(f.get())) throw InputError(path, "write failed");
}

namespace {

/// The vertex count of writePly's header; leaves `in` at the first vertex line.
std::size_t readPlyHeader(std::istream& in, const std::string& path, int& line_no) {
  static const char* const expected[] = {"ply",
                                         "format ascii 1.0",
                                         nullptr,
                                         nullptr,
                                         "property float x",
                                         "property float y",
                                         "property float z",
                                         "property uchar label",
                                         "property uchar red",
                                         "property uchar green",
                                         "property uchar blue",
                                         "end_header"};
  std::size_t count = 0;
  std::string line;
  for (const char* want : expected) {
    ++line_no;
    if (!std::getline(in, line)) throw InputError(path, line_no, "file ends inside the PLY header");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line_no == 3) {
      if (line.rfind("comment", 0) != 0) throw InputError(path, line_no, "expected the idyvins map comment");
      continue;
    }
    if (line_no == 4) {
      std::istringstream ss(line);
      std::string element, vertex, rest;
      if (!(ss >> element >> vertex >> count) || element != "element" || vertex != "vertex" || (ss >> rest))
        throw InputError(path, line_no, "expected 'element vertex N'");
      continue;
    }
    if (line != want) throw InputError(path, line_no, std::string("expected '") + want + "' (an idyvins map PLY)");
  }
  return count;
}

}  // namespace

std::vector<LabelledPoint> readPly(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open file");
  int line_no = 0;
  const std::size_t count = readPlyHeader(in, path, line_no);
  std::vector<LabelledPoint> points;
  points.reserve(count);
  std::string line;
  while (std::getline(in, line)) {
    ++line_no;
    if (points.size() == count)
      throw InputError(path, line_no, "more vertices than the header's " + std::to_string(count));
    std::istringstream ss(line);
    LabelledPoint pt;
    int r = 0, g = 0, b = 0;
    std::string rest;
    if (!(ss >> pt.p.x() >> pt.p.y() >> pt.p.z() >> pt.label >> r >> g >> b) || (ss >> rest))
      throw InputError(path, line_no, "expected 'x y z label red green blue'");
    if (pt.label < 0 || pt.label > 2) throw InputError(path, line_no, "label must be 0, 1 or 2");
    points.push_back(pt);
  }
  if (points.size() != count)
    throw InputError(path, line_no,
                     "file ends after " + std::to_string(points.size()) + " of " + std::to_string(count) + " vertices");
  return points;
}

}  // namespace idyvins::io
