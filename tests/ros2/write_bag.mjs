// Writes a ROS 2 bag from a EuRoC folder with implementations independent of idyvins
// (@mcap/core, @foxglove/rosmsg2-serialization, @foxglove/wasm-zstd, lz4js, pngjs), for the
// reader's tests.
//
// node write_bag.mjs EUROC_DIR OUT [--storage mcap|records] [--layout file|folder]
//                    [--compression none|zstd|lz4] [--encoding mono8|rgb8|png]
//                    [--groundtruth odometry|transform|pose|point|none] [--frames N] [--chunk-size BYTES]
//
// mcap + file: OUT is one .mcap; mcap + folder: OUT/ holds OUT_0.mcap and a rosbag2 metadata.yaml.
// records: OUT is a JSON list of the CDR messages (topic, type, stamp, base64) that
// ros2_bag_check.py stores in a rosbag2 sqlite3 file with Python's own sqlite3.
import fs from "node:fs";
import path from "node:path";
import { McapWriter } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";
import zstd from "@foxglove/wasm-zstd";
import lz4 from "lz4js";
import { PNG } from "pngjs";

const SEP = "\n" + "=".repeat(80) + "\n";
const DEFS = {
  "builtin_interfaces/Time": "int32 sec\nuint32 nanosec",
  "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id",
  "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z",
  "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z",
  "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
  "geometry_msgs/Pose": "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation",
  "geometry_msgs/PoseWithCovariance": "geometry_msgs/Pose pose\nfloat64[36] covariance",
  "geometry_msgs/Twist": "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular",
  "geometry_msgs/TwistWithCovariance": "geometry_msgs/Twist twist\nfloat64[36] covariance",
  "geometry_msgs/Transform": "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation",
  "sensor_msgs/Image":
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data",
  "sensor_msgs/CompressedImage": "std_msgs/Header header\nstring format\nuint8[] data",
  "sensor_msgs/Imu":
    "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n" +
    "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n" +
    "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance",
  "nav_msgs/Odometry":
    "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n" +
    "geometry_msgs/TwistWithCovariance twist",
  "geometry_msgs/TransformStamped": "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform",
  "geometry_msgs/PoseStamped": "std_msgs/Header header\ngeometry_msgs/Pose pose",
  "geometry_msgs/PointStamped": "std_msgs/Header header\ngeometry_msgs/Point point",
};

/// The ros2msg text of `type` with every dependency, as rosbag2 stores it.
function definition(type) {
  const deps = [];
  const visit = (t) => {
    for (const line of DEFS[t].split("\n")) {
      const ft = line.split(" ")[0].replace(/\[.*$/, "");
      if (DEFS[ft] && !deps.includes(ft)) {
        deps.push(ft);
        visit(ft);
      }
    }
  };
  visit(type);
  return DEFS[type] + deps.map((d) => SEP + "MSG: " + d + "\n" + DEFS[d]).join("");
}

function args() {
  const a = { storage: "mcap", layout: "file", compression: "none", encoding: "mono8", groundtruth: "odometry",
              frames: 0, "chunk-size": 1 << 20 };
  const pos = [];
  for (let i = 2; i < process.argv.length; ++i) {
    const k = process.argv[i];
    if (k.startsWith("--")) a[k.slice(2)] = process.argv[++i];
    else pos.push(k);
  }
  if (pos.length !== 2) throw new Error("usage: write_bag.mjs EUROC_DIR OUT [options]");
  [a.euroc, a.out] = pos;
  a.frames = Number(a.frames);
  a["chunk-size"] = Number(a["chunk-size"]);
  return a;
}

function rows(file) {
  return fs.readFileSync(file, "utf8").split("\n").filter((l) => l.trim() && !l.startsWith("#"))
    .map((l) => l.split(",").map((c) => c.trim()));
}

const stampOf = (ns) => ({ sec: Number(ns / 1000000000n), nanosec: Number(ns % 1000000000n) });

function imageMessage(file, ns, encoding) {
  const header = { stamp: stampOf(ns), frame_id: "cam" };
  if (encoding === "png")
    return { header, format: "mono8; png compressed ", data: new Uint8Array(fs.readFileSync(file)) };
  const png = PNG.sync.read(fs.readFileSync(file));
  const ch = encoding === "mono8" ? 1 : 3;
  const data = new Uint8Array(png.width * png.height * ch);
  for (let i = 0; i < png.width * png.height; ++i)
    for (let c = 0; c < ch; ++c) data[i * ch + c] = png.data[i * 4];  // gray: every channel alike
  return { header, height: png.height, width: png.width, encoding, is_bigendian: 0, step: png.width * ch, data };
}

function groundTruthMessage(kind, r) {
  const ns = BigInt(r[0]);
  const header = { stamp: stampOf(ns), frame_id: "world" };
  const [px, py, pz, qw, qx, qy, qz] = r.slice(1, 8).map(Number);
  const position = { x: px, y: py, z: pz }, orientation = { x: qx, y: qy, z: qz, w: qw };
  if (kind === "odometry")
    return { header, child_frame_id: "body", pose: { pose: { position, orientation }, covariance: new Float64Array(36) },
             twist: { twist: { linear: { x: 0, y: 0, z: 0 }, angular: { x: 0, y: 0, z: 0 } },
                      covariance: new Float64Array(36) } };
  if (kind === "transform")
    return { header, child_frame_id: "body", transform: { translation: position, rotation: orientation } };
  if (kind === "pose") return { header, pose: { position, orientation } };
  return { header, point: position };
}

const GT = { odometry: ["/odometry", "nav_msgs/Odometry"],
             transform: ["/vicon/firefly_sbx/firefly_sbx", "geometry_msgs/TransformStamped"],
             pose: ["/pose", "geometry_msgs/PoseStamped"], point: ["/leica/position", "geometry_msgs/PointStamped"] };

/// Every message in stamp order: [topic, type (ROS 2 spelling), stamp ns, message object].
function messages(a) {
  const mav0 = path.join(a.euroc, "mav0");
  const out = [];
  for (const r of rows(path.join(mav0, "imu0", "data.csv"))) {
    const ns = BigInt(r[0]);
    const [wx, wy, wz, ax, ay, az] = r.slice(1, 7).map(Number);
    out.push(["/imu0", "sensor_msgs/Imu", ns, {
      header: { stamp: stampOf(ns), frame_id: "imu" }, orientation: { x: 0, y: 0, z: 0, w: 1 },
      orientation_covariance: Float64Array.from([-1, 0, 0, 0, 0, 0, 0, 0, 0]),
      angular_velocity: { x: wx, y: wy, z: wz }, angular_velocity_covariance: new Float64Array(9),
      linear_acceleration: { x: ax, y: ay, z: az }, linear_acceleration_covariance: new Float64Array(9) }]);
  }
  const png = a.encoding === "png";
  let last = null;
  for (const cam of ["cam0", "cam1"]) {
    let k = 0;
    for (const r of rows(path.join(mav0, cam, "data.csv"))) {
      if (a.frames && ++k > a.frames) break;
      const ns = BigInt(r[0]);
      if (cam === "cam0") last = ns;
      out.push(["/" + cam + "/image_raw" + (png ? "/compressed" : ""),
                png ? "sensor_msgs/CompressedImage" : "sensor_msgs/Image", ns,
                path.join(mav0, cam, "data", r[1])]);
    }
  }
  const gtFile = path.join(mav0, "state_groundtruth_estimate0", "data.csv");
  if (a.groundtruth !== "none" && fs.existsSync(gtFile))
    for (const r of rows(gtFile)) out.push([GT[a.groundtruth][0], GT[a.groundtruth][1], BigInt(r[0]), r]);
  const kept = out.filter((m) => !a.frames || m[2] <= last + 100000000n);
  kept.sort((x, y) => (x[2] < y[2] ? -1 : x[2] > y[2] ? 1 : 0));
  return kept.map(([topic, type, ns, payload]) => [topic, type.replace("/", "/msg/"), ns, payload]);
}

const writers = {};
/// The CDR bytes of one message (an image file, a ground-truth row or a message object).
function cdr(type, ns, payload, a) {
  const base = type.replace("/msg/", "/");
  writers[base] ??= new MessageWriter(parse(definition(base), { ros2: true }));
  const msg = typeof payload === "string" ? imageMessage(payload, ns, a.encoding)
    : Array.isArray(payload) ? groundTruthMessage(a.groundtruth, payload) : payload;
  return writers[base].writeMessage(msg);
}

async function writeMcap(a, list, file) {
  await zstd.isLoaded;
  const chunks = [];
  let size = 0n;
  const writable = { position: () => size, write: async (b) => { chunks.push(Buffer.from(b)); size += BigInt(b.length); } };
  const compressChunk = a.compression === "none" ? undefined
    : (data) => ({ compression: a.compression,
                   compressedData: a.compression === "zstd" ? zstd.compress(data, 3) : lz4.compress(data) });
  const w = new McapWriter({ writable, useStatistics: true, useChunks: true, useChunkIndex: true,
                             chunkSize: a["chunk-size"], compressChunk });
  await w.start({ profile: "ros2", library: "idyvins tests (@mcap/core)" });
  const channels = {};
  let seq = 0;
  for (const [topic, type, ns, payload] of list) {
    if (!(topic in channels)) {
      const base = type.replace("/msg/", "/");
      const schemaId = await w.registerSchema({ name: type, encoding: "ros2msg",
                                                data: new TextEncoder().encode(definition(base)) });
      channels[topic] = await w.registerChannel({ topic, messageEncoding: "cdr", schemaId, metadata: new Map() });
    }
    await w.addMessage({ channelId: channels[topic], sequence: seq++, logTime: ns, publishTime: ns,
                         data: cdr(type, ns, payload, a) });
  }
  await w.end();
  fs.writeFileSync(file, Buffer.concat(chunks));
  return { count: seq };
}

async function main() {
  const a = args();
  const list = messages(a);
  if (a.storage === "records") {
    const topics = {};
    const records = list.map(([topic, type, ns, payload]) => {
      topics[topic] = type;
      return [topic, ns.toString(), Buffer.from(cdr(type, ns, payload, a)).toString("base64")];
    });
    fs.writeFileSync(a.out, JSON.stringify({ topics, records }));
    return;
  }
  if (a.layout === "file") return void (await writeMcap(a, list, a.out));
  fs.mkdirSync(a.out, { recursive: true });
  const name = path.basename(a.out) + "_0.mcap";
  await writeMcap(a, list, path.join(a.out, name));
  const counts = {};
  for (const [topic, type] of list) counts[topic] = [type, (counts[topic]?.[1] ?? 0) + 1];
  const start = list[0][2], end = list[list.length - 1][2];
  fs.writeFileSync(path.join(a.out, "metadata.yaml"), [
    "rosbag2_bagfile_information:", "  version: 5", "  storage_identifier: mcap",
    "  duration:", `    nanoseconds: ${end - start}`, "  starting_time:", `    nanoseconds_since_epoch: ${start}`,
    `  message_count: ${list.length}`, "  topics_with_message_count:",
    ...Object.entries(counts).flatMap(([t, [type, n]]) => [
      "    - topic_metadata:", `        name: ${t}`, `        type: ${type}`, "        serialization_format: cdr",
      '        offered_qos_profiles: ""', `      message_count: ${n}`]),
    '  compression_format: ""', '  compression_mode: ""', "  relative_file_paths:", `    - ${name}`, ""].join("\n"));
}

main().catch((e) => { console.error(e.stack ?? String(e)); process.exit(1); });
