// Decode every cdr channel of an MCAP file with Foxglove's own ROS 2 libraries
// (@foxglove/rosmsg parse with ros2: true, @foxglove/rosmsg2-serialization MessageReader,
// @mcap/core reader: what Foxglove Studio uses). Prints {file, ok, bad, errors} as JSON.
//   node foxglove_ros2_decode.mjs FILE.mcap   (NODE_PATH: a node_modules with the three)
// Written uncompressed or zstd: this script has no lz4 decompressor.
import { readFileSync } from "node:fs";
import { McapIndexedReader } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";

const file = process.argv[2];
const data = readFileSync(file);
const readable = {
  size: async () => BigInt(data.length),
  read: async (offset, length) => data.subarray(Number(offset), Number(offset + length)),
};
const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers: {
  lz4: (buf, size) => { throw new Error("lz4 not supported here"); },
}});
const readers = new Map();
let ok = 0, bad = 0; const errors = {};
for await (const msg of reader.readMessages()) {
  const channel = reader.channelsById.get(msg.channelId);
  if (channel.messageEncoding !== "cdr") continue;
  try {
    let r = readers.get(channel.id);
    if (!r) {
      const schema = reader.schemasById.get(channel.schemaId);
      r = new MessageReader(parse(new TextDecoder().decode(schema.data), { ros2: true }));
      readers.set(channel.id, r);
    }
    r.readMessage(msg.data); ok++;
  } catch (e) { bad++; errors[channel.topic] = String(e).slice(0, 120); }
}
console.log(JSON.stringify({ file, ok, bad, errors }));
