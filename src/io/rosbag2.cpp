// ROS 2 bags without ROS 2: rosbag2 folders (metadata.yaml naming .mcap or .db3 files) and bare
// .mcap / .db3 files, messages in CDR (ros2_messages.h), behind BagFile.

#include <sqlite3.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <map>
#include <set>

#include "core/error.h"
#include "io/bag_file.h"
#include "io/mcap.h"
#include "io/ros2_messages.h"

namespace idyvins::io {
namespace {

namespace fs = std::filesystem;

/// One topic of one storage file.
struct StorageTopic {
  std::string name, type, serialization;
  std::size_t count = 0;
};

/// One storage file: its topics, and one pass over the messages of some of them.
class Storage {
 public:
  virtual ~Storage() = default;
  virtual std::vector<StorageTopic> topics() = 0;
  virtual void start(const std::set<std::string>& topics) = 0;
  /// The next message of the pass: its topic (valid while the storage lives) and bytes.
  virtual bool next(const std::string*& topic, const std::uint8_t*& data, std::size_t& size) = 0;
  virtual std::string describe() const = 0;
};

class McapStorage : public Storage {
 public:
  explicit McapStorage(const std::string& path) : reader_(path) {}
  std::vector<StorageTopic> topics() override {
    std::map<std::uint16_t, McapChannel> channels;
    std::map<std::uint16_t, std::uint64_t> counts;
    if (!reader_.summary(channels, counts)) {  // no statistics: count them
      McapMessage m;
      while (reader_.next(m)) ++counts[m.channel_id];
      for (const auto& [id, n] : counts) channels[id] = *reader_.channel(id);
      reader_.rewind();
    }
    std::map<std::string, StorageTopic> by_name;
    for (const auto& [id, c] : channels) {
      StorageTopic& t = by_name[c.topic];
      t.name = c.topic;
      t.type = c.schema_name;
      t.serialization = c.message_encoding;
      t.count += counts.count(id) ? static_cast<std::size_t>(counts.at(id)) : 0;
    }
    std::vector<StorageTopic> out;
    for (auto& [name, t] : by_name) out.push_back(std::move(t));
    return out;
  }
  void start(const std::set<std::string>& topics) override {
    reader_.rewind();
    wanted_ = topics;
  }
  bool next(const std::string*& topic, const std::uint8_t*& data, std::size_t& size) override {
    McapMessage m;
    while (reader_.next(m)) {
      const McapChannel* c = reader_.channel(m.channel_id);
      if (!wanted_.count(c->topic)) continue;
      topic = &*wanted_.find(c->topic);
      data = m.data;
      size = m.size;
      return true;
    }
    return false;
  }
  std::string describe() const override {
    std::string chunks;
    for (const std::string& c : reader_.compressions()) chunks += (chunks.empty() ? "" : "/") + c;
    return "mcap" + (chunks.empty() ? std::string() : ", chunks " + chunks);
  }

 private:
  McapReader reader_;
  std::set<std::string> wanted_;
};

class SqliteStorage : public Storage {
 public:
  explicit SqliteStorage(const std::string& path) : path_(path) {
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) fail("cannot open");
  }
  ~SqliteStorage() override {
    sqlite3_finalize(stmt_);
    sqlite3_close(db_);
  }
  std::vector<StorageTopic> topics() override {
    std::map<std::int64_t, StorageTopic> by_id;
    prepare("SELECT id, name, type, serialization_format FROM topics", "reading the topics table");
    while (step()) {
      StorageTopic& t = by_id[sqlite3_column_int64(stmt_, 0)];
      t.name = text(1);
      t.type = text(2);
      t.serialization = text(3);
    }
    prepare("SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id", "counting the messages");
    while (step()) {
      const auto it = by_id.find(sqlite3_column_int64(stmt_, 0));
      if (it == by_id.end()) fail("messages name a topic_id the topics table does not have");
      it->second.count = static_cast<std::size_t>(sqlite3_column_int64(stmt_, 1));
    }
    std::vector<StorageTopic> out;
    for (auto& [id, t] : by_id) {
      name_of_id_[id] = t.name;
      out.push_back(t);
    }
    return out;
  }
  void start(const std::set<std::string>& topics) override {
    if (name_of_id_.empty()) this->topics();
    std::string ids;
    for (const auto& [id, name] : name_of_id_)
      if (topics.count(name)) ids += (ids.empty() ? "" : ",") + std::to_string(id);
    prepare("SELECT topic_id, data FROM messages WHERE topic_id IN (" + ids + ") ORDER BY timestamp, id",
            "reading the messages");
  }
  bool next(const std::string*& topic, const std::uint8_t*& data, std::size_t& size) override {
    if (!step()) return false;
    topic = &name_of_id_.at(sqlite3_column_int64(stmt_, 0));
    data = static_cast<const std::uint8_t*>(sqlite3_column_blob(stmt_, 1));
    size = static_cast<std::size_t>(sqlite3_column_bytes(stmt_, 1));
    return true;
  }
  std::string describe() const override { return "sqlite3"; }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path_, "not a readable rosbag2 sqlite3 file (damaged?): " + what + ": " +
                                (db_ ? sqlite3_errmsg(db_) : "no database"));
  }
  void prepare(const std::string& sql, const std::string& what) {
    sqlite3_finalize(stmt_);
    stmt_ = nullptr;
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt_, nullptr) != SQLITE_OK) fail(what);
  }
  bool step() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail("reading a row");
  }
  std::string text(int column) const {
    const unsigned char* t = sqlite3_column_text(stmt_, column);
    return t ? reinterpret_cast<const char*>(t) : "";
  }
  std::string path_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* stmt_ = nullptr;
  std::map<std::int64_t, std::string> name_of_id_;
};

std::unique_ptr<Storage> openStorage(const std::string& path) {
  if (!fs::is_regular_file(path)) throw InputError(path, "no such file (named by the bag's metadata.yaml)");
  if (bagFormat(path) != BagFormat::kRos2 || fs::is_directory(path))
    throw InputError(path, "neither an MCAP nor a sqlite3 file");
  std::ifstream in(path, std::ios::binary);
  char c = 0;
  in.get(c);
  if (c == 'S') return std::make_unique<SqliteStorage>(path);
  return std::make_unique<McapStorage>(path);
}

/// A YAML node's line (1-based) for messages.
int lineOf(const YAML::Node& n) { return n.Mark().line + 1; }

/// The storage files a rosbag2 folder's metadata.yaml names.
std::vector<std::string> filesOfFolder(const std::string& folder) {
  const std::string meta = (fs::path(folder) / "metadata.yaml").string();
  YAML::Node root;
  try {
    root = YAML::LoadFile(meta);
  } catch (const YAML::Exception& e) {
    throw InputError(meta, e.mark.line + 1, std::string("not valid YAML: ") + e.msg);
  }
  const YAML::Node info = root["rosbag2_bagfile_information"];
  if (!info || !info.IsMap()) throw InputError(meta, "expected the key rosbag2_bagfile_information");
  const std::string storage = info["storage_identifier"] ? info["storage_identifier"].as<std::string>("") : "";
  if (storage != "mcap" && storage != "sqlite3")
    throw InputError(meta, info["storage_identifier"] ? lineOf(info["storage_identifier"]) : 0,
                     "storage_identifier '" + storage + "' is not read (mcap, sqlite3)");
  const std::string compression = info["compression_format"] ? info["compression_format"].as<std::string>("") : "";
  if (!compression.empty())
    throw InputError(meta, lineOf(info["compression_format"]),
                     "compression_format '" + compression +
                         "': compressed rosbag2 files are not read; decompress them (zstd -d) and open the ." +
                         (storage == "mcap" ? "mcap" : "db3") + " files");
  const YAML::Node paths = info["relative_file_paths"];
  if (!paths || !paths.IsSequence() || paths.size() == 0)
    throw InputError(meta, "expected relative_file_paths, a list of the bag's files");
  std::vector<std::string> files;
  for (const YAML::Node& p : paths) files.push_back((fs::path(folder) / p.as<std::string>()).string());
  return files;
}

class Ros2Cursor : public BagCursor {
 public:
  Ros2Cursor(std::vector<Storage*> storages, const std::set<std::string>& topics,
             const std::map<std::string, std::string>& serialization)
      : storages_(std::move(storages)), topics_(topics), serialization_(serialization) {
    if (!storages_.empty()) storages_[0]->start(topics_);
  }
  bool next() override {
    while (k_ < storages_.size()) {
      if (storages_[k_]->next(topic_, data_, size_)) return true;
      if (++k_ < storages_.size()) storages_[k_]->start(topics_);
    }
    return false;
  }
  const std::string& topic() const override { return *topic_; }
  BagImage image(BagMessageKind kind) override { return checked(), decodeRos2Image(data_, size_, kind); }
  ImuSample imu() override { return checked(), decodeRos2Imu(data_, size_); }
  BagPose pose(BagMessageKind kind) override { return checked(), decodeRos2Pose(data_, size_, kind); }

 private:
  void checked() const {
    const std::string& s = serialization_.at(*topic_);
    if (s != "cdr") throw BagMessageError("serialized as '" + s + "', not cdr");
  }
  std::vector<Storage*> storages_;
  std::set<std::string> topics_;
  const std::map<std::string, std::string>& serialization_;
  std::size_t k_ = 0;
  const std::string* topic_ = nullptr;
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
};

class Ros2Bag : public BagFile {
 public:
  explicit Ros2Bag(const std::string& path) {
    const std::vector<std::string> files = fs::is_directory(path) ? filesOfFolder(path) : std::vector{path};
    std::map<std::string, BagTopicInfo> merged;
    for (const std::string& f : files) {
      storages_.push_back(openStorage(f));
      for (const StorageTopic& t : storages_.back()->topics()) {
        BagTopicInfo& m = merged[t.name];
        if (!m.type.empty() && m.type != t.type)
          throw InputError(f, "topic '" + t.name + "' has type " + t.type + " here and " + m.type + " before");
        m.topic = t.name;
        m.type = t.type;
        m.count += t.count;
        serialization_[t.name] = t.serialization;
      }
    }
    for (auto& [name, t] : merged) topics_.push_back(t);
  }
  const std::vector<BagTopicInfo>& topics() const override { return topics_; }
  std::unique_ptr<BagCursor> read(const std::vector<std::string>& topics) override {
    std::vector<Storage*> s;
    for (auto& p : storages_) s.push_back(p.get());
    return std::make_unique<Ros2Cursor>(s, std::set<std::string>(topics.begin(), topics.end()), serialization_);
  }
  std::string format() const override {
    std::set<std::string> kinds;
    for (const auto& s : storages_) kinds.insert(s->describe());
    std::string out;
    for (const std::string& k : kinds) out += (out.empty() ? "" : "; ") + k;
    return "ROS 2 bag (" + out + ")";
  }

 private:
  std::vector<std::unique_ptr<Storage>> storages_;
  std::vector<BagTopicInfo> topics_;
  std::map<std::string, std::string> serialization_;
};

}  // namespace

std::unique_ptr<BagFile> openRos2Bag(const std::string& path) { return std::make_unique<Ros2Bag>(path); }

}  // namespace idyvins::io
