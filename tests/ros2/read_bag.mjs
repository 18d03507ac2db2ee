// Reads an MCAP file with @mcap/core (indexed: through its summary and chunk indexes; and as a
// stream: every record and chunk CRC) and decodes its messages with
// @foxglove/rosmsg2-serialization, from the schemas the file carries: an implementation
// independent of idyvins' writer (simulate --format mcap). Prints JSON for ros2_bag_check.py.
//
// node read_bag.mjs FILE.mcap
import fs from "node:fs";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import zstd from "@foxglove/wasm-zstd";
import lz4 from "lz4js";

const decompressHandlers = {
  zstd: (buf, size) => zstd.decompress(buf, Number(size)),
  lz4: (buf, size) => { const out = lz4.decompress(buf, Number(size)); return Uint8Array.from(out); },
};

function summarize(type, m) {
  const t = (h) => Number(h.stamp.sec) * 1e9 + Number(h.stamp.nanosec);
  if (type.endsWith("/Image")) {
    let sum = 0;
    for (const v of m.data) sum += v;
    return { stamp: t(m.header), width: m.width, height: m.height, encoding: m.encoding, step: m.step,
             bytes: m.data.length, sum };
  }
  if (type.endsWith("/Imu"))
    return { stamp: t(m.header), gyr: [m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z],
             acc: [m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z],
             orientation_covariance0: m.orientation_covariance[0] };
  if (type.endsWith("/Odometry")) {
    const p = m.pose.pose;
    return { stamp: t(m.header), p: [p.position.x, p.position.y, p.position.z],
             q: [p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z] };
  }
  return {};
}

async function main() {
  await zstd.isLoaded;
  const file = process.argv[2];
  const bytes = fs.readFileSync(file);
  const readable = { size: async () => BigInt(bytes.length),
                     read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)) };
  const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  const out = { profile: reader.header.profile, topics: {}, statistics: null, first: {}, stream_records: 0 };
  const readers = {};
  for (const [id, c] of reader.channelsById) {
    const s = reader.schemasById.get(c.schemaId);
    out.topics[c.topic] = { type: s.name, schema_encoding: s.encoding, message_encoding: c.messageEncoding, count: 0 };
    readers[id] = new MessageReader(parse(new TextDecoder().decode(s.data), { ros2: true }));
  }
  if (reader.statistics)
    out.statistics = { message_count: Number(reader.statistics.messageCount), chunk_count: reader.statistics.chunkCount };
  let last = {};
  for await (const msg of reader.readMessages()) {
    const c = reader.channelsById.get(msg.channelId);
    const topic = out.topics[c.topic];
    ++topic.count;
    const decoded = readers[msg.channelId].readMessage(msg.data);
    const s = summarize(topic.type, decoded);
    if (!(c.topic in out.first)) out.first[c.topic] = s;
    if (last[c.topic] !== undefined && BigInt(msg.logTime) < last[c.topic]) throw new Error("log times go back");
    last[c.topic] = BigInt(msg.logTime);
  }
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  stream.append(bytes);
  for (let r; (r = stream.nextRecord()); ) ++out.stream_records;
  if (!stream.done()) throw new Error("the stream reader did not reach the end magic");
  console.log(JSON.stringify(out));
}

main().catch((e) => { console.error(e.stack ?? String(e)); process.exit(1); });
