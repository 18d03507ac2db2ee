#include "io/ply.h"

#include <cstdio>
#include <memory>

#include "core/error.h"

namespace idyvins::io {

int plyLabel(FeatureLabel label) {
  switch (label) {
    case FeatureLabel::kEliminated: return 1;
    case FeatureLabel::kConfirmedDynamic: return 2;
    default: return 0;
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

}  // namespace idyvins::io
