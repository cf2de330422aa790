#include "colorfree/perception/cnn/dataset.h"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "colorfree/perception/error.h"

namespace colorfree::cnn {

namespace fs = std::filesystem;

namespace {

constexpr const char* kManifestHeader =
    "file,label,scenario,frame,x_px,y_px,width_px,height_px,truth";

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

template <typename T>
T parseNumber(const std::string& text, const std::string& where, const char* column) {
  T value{};
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) {
    throw Error(where + ": column " + column + " '" + text + "' is not a number");
  }
  return value;
}

struct ManifestRow {
  std::string label;
  SampleOrigin origin;
};

std::map<std::string, ManifestRow> readManifest(const std::string& path) {
  std::map<std::string, ManifestRow> rows;
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open manifest");
  std::string line;
  if (std::getline(in, line) && !line.empty() && line.back() == '\r') line.pop_back();
  if (line != kManifestHeader) {
    throw Error(path + ": first line must be '" + std::string(kManifestHeader) + "'");
  }
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const std::string where = path + ":" + std::to_string(line_no);
    const auto cols = splitCsv(line);
    if (cols.size() != 9) {
      throw Error(where + ": expected 9 comma-separated columns, got " +
                  std::to_string(cols.size()));
    }
    ManifestRow row;
    row.label = cols[1];
    row.origin.file = cols[0];
    row.origin.scenario = cols[2];
    row.origin.frame = cols[3].empty() ? -1 : parseNumber<int>(cols[3], where, "frame");
    row.origin.x_px = cols[4].empty() ? 0.0f : parseNumber<float>(cols[4], where, "x_px");
    row.origin.y_px = cols[5].empty() ? 0.0f : parseNumber<float>(cols[5], where, "y_px");
    row.origin.width_px = cols[6].empty() ? 0.0f : parseNumber<float>(cols[6], where, "width_px");
    row.origin.height_px = cols[7].empty() ? 0.0f : parseNumber<float>(cols[7], where, "height_px");
    row.origin.truth = cols[8];
    if (!rows.emplace(cols[0], row).second)
      throw Error(where + ": file " + cols[0] + " listed twice");
  }
  return rows;
}

}  // namespace

std::vector<int> Dataset::classCounts() const {
  std::vector<int> counts(class_names.size(), 0);
  for (const Sample& s : samples) {
    if (s.label >= 0 && s.label < static_cast<int>(counts.size())) ++counts[s.label];
  }
  return counts;
}

Dataset readDataset(const std::string& dir, int width, int height,
                    const std::vector<std::string>& class_names) {
  if (!fs::is_directory(dir)) throw Error(dir + ": dataset folder does not exist");
  Dataset data;
  data.width = width;
  data.height = height;
  data.class_names = class_names;
  if (data.class_names.empty()) {
    for (const auto& e : fs::directory_iterator(dir)) {
      if (e.is_directory()) data.class_names.push_back(e.path().filename().string());
    }
    std::sort(data.class_names.begin(), data.class_names.end());
  }
  if (data.class_names.size() < 2)
    throw Error(dir + ": a dataset needs at least two class folders");
  const std::string manifest_path = (fs::path(dir) / kManifestName).string();
  std::map<std::string, ManifestRow> manifest;
  if (fs::exists(manifest_path)) manifest = readManifest(manifest_path);
  std::size_t listed_found = 0;
  for (int label = 0; label < static_cast<int>(data.class_names.size()); ++label) {
    const fs::path class_dir = fs::path(dir) / data.class_names[label];
    if (!fs::is_directory(class_dir))
      throw Error(class_dir.string() + ": class folder does not exist");
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(class_dir)) {
      if (e.is_regular_file() && e.path().extension() == ".png")
        files.push_back(e.path().filename().string());
    }
    std::sort(files.begin(), files.end());
    for (const std::string& name : files) {
      const std::string rel = data.class_names[label] + "/" + name;
      const std::string path = (class_dir / name).string();
      Sample s;
      s.patch = readGrayImage(path);
      if (s.patch.width() != width || s.patch.height() != height) {
        throw Error(path + ": patch is " + std::to_string(s.patch.width()) + "x" +
                    std::to_string(s.patch.height()) + ", the net needs " + std::to_string(width) +
                    "x" + std::to_string(height));
      }
      s.label = label;
      const auto it = manifest.find(rel);
      if (it != manifest.end()) {
        if (it->second.label != data.class_names[label]) {
          throw Error(manifest_path + ": " + rel + " is labelled '" + it->second.label +
                      "' but lies in folder '" + data.class_names[label] + "'");
        }
        s.origin = it->second.origin;
        ++listed_found;
      } else {
        s.origin.file = rel;
      }
      data.samples.push_back(std::move(s));
    }
  }
  if (listed_found != manifest.size()) {
    for (const auto& [file, row] : manifest) {
      if (!fs::exists(fs::path(dir) / file)) {
        throw Error(manifest_path + ": lists " + file + ", which does not exist");
      }
    }
    throw Error(manifest_path + ": lists files outside the class folders");
  }
  return data;
}

void writeDataset(const Dataset& data, const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error(dir + ": cannot create dataset folder: " + ec.message());
  for (const std::string& name : data.class_names) {
    fs::create_directories(fs::path(dir) / name, ec);
    if (ec) throw Error(dir + "/" + name + ": cannot create class folder: " + ec.message());
  }
  std::ostringstream manifest;
  manifest << kManifestHeader << "\n";
  std::vector<int> counter(data.class_names.size(), 0);
  for (const Sample& s : data.samples) {
    if (s.label < 0 || s.label >= static_cast<int>(data.class_names.size())) {
      throw Error(dir + ": sample with label " + std::to_string(s.label) + " has no class name");
    }
    if (s.patch.width() != data.width || s.patch.height() != data.height) {
      throw Error(dir + ": sample " + s.origin.file + " is not " + std::to_string(data.width) +
                  "x" + std::to_string(data.height));
    }
    const std::string& cls = data.class_names[s.label];
    std::string rel = s.origin.file;
    if (rel.empty() || rel.rfind(cls + "/", 0) != 0) {
      char name[32];
      std::snprintf(name, sizeof(name), "%06d.png", counter[s.label]);
      rel = cls + "/" + name;
    }
    ++counter[s.label];
    writeGrayPng((fs::path(dir) / rel).string(), s.patch.view());
    std::string truth = s.origin.truth;
    std::replace(truth.begin(), truth.end(), ',', ';');
    std::string scenario = s.origin.scenario;
    std::replace(scenario.begin(), scenario.end(), ',', ';');
    manifest << rel << "," << cls << "," << scenario << "," << s.origin.frame << ","
             << s.origin.x_px << "," << s.origin.y_px << "," << s.origin.width_px << ","
             << s.origin.height_px << "," << truth << "\n";
  }
  const fs::path final_path = fs::path(dir) / kManifestName;
  const fs::path tmp = final_path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << manifest.str();
    out.close();
    if (!out) throw Error(tmp.string() + ": cannot write manifest");
  }
  fs::rename(tmp, final_path, ec);
  if (ec) throw Error(final_path.string() + ": cannot rename manifest: " + ec.message());
}

}  // namespace colorfree::cnn
