// Foxglove's own WebSocket protocol client (@foxglove/ws-protocol, the library the
// Foxglove and Lichtblick apps connect with), over the `ws` package: subscribe to every
// channel as it is advertised and print one JSON line per message received, until the
// server closes.  node foxglove_ws_client.js ws://127.0.0.1:PORT
const crypto = require("crypto");
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const WebSocket = require("ws");

const ws = new WebSocket(process.argv[2], ["foxglove.sdk.v1"]);
const client = new FoxgloveClient({ ws });
const advertised = new Set();
const subscribed = new Map();
client.on("advertise", (channels) => {
  for (const channel of channels) {
    if (advertised.has(channel.id)) continue;
    advertised.add(channel.id);
    subscribed.set(client.subscribe(channel.id), channel);
    process.stdout.write(JSON.stringify({ advertised: channel.topic, schemaName: channel.schemaName, encoding: channel.encoding }) + "\n");
  }
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const channel = subscribed.get(subscriptionId);
  const bytes = Buffer.from(data.buffer, data.byteOffset, data.byteLength);
  const sha1 = crypto.createHash("sha1").update(bytes).digest("hex");
  process.stdout.write(JSON.stringify({ topic: channel.topic, log_time: timestamp.toString(), sha1 }) + "\n");
});
client.on("error", (error) => process.stderr.write(`error: ${error}\n`));
client.on("close", () => process.exit(0));
