// VIODE's segmentation colours (io/bag_dataset.h): the colour tables and the masks made with them.

#include <fstream>
#include <map>
#include <opencv2/core.hpp>

#include "core/error.h"
#include "io/bag_dataset.h"

namespace idyvins::io {
namespace {

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  for (char c : line) {
    if (c == ',') {
      out.push_back(cell);
      cell.clear();
    } else if (c != ' ' && c != '\t' && c != '\r') {
      cell += c;
    }
  }
  out.push_back(cell);
  return out;
}

int parseInt(const std::string& text, const std::string& path, int line, int lo, int hi) {
  try {
    std::size_t used = 0;
    const int v = std::stoi(text, &used);
    if (used == text.size() && v >= lo && v <= hi) return v;
  } catch (const std::exception&) {
  }
  throw InputError(
      path, line,
      "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got '" + text + "'");
}

}  // namespace

SegmentationColors readSegmentationColors(const std::string& rgb_ids_path, const std::string& vehicle_ids_path) {
  auto lines = [](const std::string& path) {
    std::ifstream in(path);
    if (!in) throw InputError(path, "cannot open");
    std::vector<std::string> out;
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
  };
  // Moving vehicles, in file order: their mask value is 1 + position.
  std::map<int, std::uint8_t> label_of_id;
  const auto vehicles = lines(vehicle_ids_path);
  for (std::size_t i = 1; i < vehicles.size(); ++i) {  // line 1: header
    if (vehicles[i].find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto cells = splitCsv(vehicles[i]);
    if (cells.size() != 2) throw InputError(vehicle_ids_path, static_cast<int>(i + 1), "expected 'id, name'");
    const int id = parseInt(cells[0], vehicle_ids_path, static_cast<int>(i + 1), 0, 255);
    if (cells[1].find("dynamic") != std::string::npos) {
      if (label_of_id.size() >= 255) throw InputError(vehicle_ids_path, "more than 255 moving vehicles");
      label_of_id[id] = static_cast<std::uint8_t>(label_of_id.size() + 1);
    }
  }
  SegmentationColors colors;
  const auto rgb = lines(rgb_ids_path);
  for (std::size_t i = 1; i < rgb.size(); ++i) {
    if (rgb[i].find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto cells = splitCsv(rgb[i]);
    const int line = static_cast<int>(i + 1);
    if (cells.size() != 4) throw InputError(rgb_ids_path, line, "expected 'id,r,g,b'");
    const int id = parseInt(cells[0], rgb_ids_path, line, 0, 255);
    const std::uint32_t key = (static_cast<std::uint32_t>(parseInt(cells[1], rgb_ids_path, line, 0, 255)) << 16) |
                              (static_cast<std::uint32_t>(parseInt(cells[2], rgb_ids_path, line, 0, 255)) << 8) |
                              static_cast<std::uint32_t>(parseInt(cells[3], rgb_ids_path, line, 0, 255));
    const auto it = label_of_id.find(id);
    colors.label_of_rgb[key] = it == label_of_id.end() ? 0 : it->second;
  }
  return colors;
}

cv::Mat labelsFromColors(const cv::Mat& rgb, const SegmentationColors& colors) {
  cv::Mat labels(rgb.size(), CV_8UC1, cv::Scalar(0));
  for (int y = 0; y < rgb.rows; ++y) {
    const cv::Vec3b* in = rgb.ptr<cv::Vec3b>(y);
    uchar* out = labels.ptr<uchar>(y);
    for (int x = 0; x < rgb.cols; ++x) {
      const std::uint32_t key =
          (static_cast<std::uint32_t>(in[x][0]) << 16) | (static_cast<std::uint32_t>(in[x][1]) << 8) | in[x][2];
      const auto it = colors.label_of_rgb.find(key);
      out[x] = it == colors.label_of_rgb.end() ? 0 : it->second;
    }
  }
  return labels;
}

}  // namespace idyvins::io
