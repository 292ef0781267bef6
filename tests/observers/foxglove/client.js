// Foxglove's own WebSocket protocol client (@foxglove/ws-protocol) on the executive's live server, as Foxglove connects.
// node client.js URL [--stall]: prints one JSON line per event ("subscribed", then "done" with what it received);
// subscribes to every channel advertised; ends once it has the run's end (/mission/state COMPLETED or ABORTED, and the
// /tree/tick of the run's end: two channels, in either order), or 20 s after its stdin closes.
// --stall: subscribes, then never reads again (its socket paused): the server must drop for it, never wait.
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const WebSocket = require("ws");

const [url, mode] = process.argv.slice(2);
// the SDK's server (foxglove-sdk 0.30) speaks the protocol as "foxglove.sdk.v1" only; this client's own name for it is offered too
const ws = new WebSocket(url, ["foxglove.sdk.v1", FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
const client = new FoxgloveClient({ ws });
const channels = new Map(); // subscription id -> channel
const received = {}; // topic -> { count, first, last, schemaName, encoding }
let serverName = null;
const ended = { state: false, tick: false };
const say = (event) => process.stdout.write(JSON.stringify(event) + "\n");

function finish() {
  say({ event: "done", serverName, received });
  client.close();
  process.exit(0);
}

client.on("serverInfo", (info) => { serverName = info.name; });
client.on("advertise", (advertised) => {
  for (const channel of advertised) channels.set(client.subscribe(channel.id), channel);
  say({ event: "subscribed", topics: advertised.map((c) => c.topic) });
  if (mode === "--stall") ws._socket.pause();
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const channel = channels.get(subscriptionId);
  const body = JSON.parse(new TextDecoder().decode(data));
  const seen = received[channel.topic] ??= { count: 0, schemaName: channel.schemaName, encoding: channel.encoding };
  seen.count += 1;
  seen.first ??= { timestamp: Number(timestamp), body };
  seen.last = { timestamp: Number(timestamp), body };
  if (channel.topic === "/mission/state" && ["COMPLETED", "ABORTED"].includes(body.state)) ended.state = true;
  if (channel.topic === "/tree/tick" && body.end) ended.tick = true;
  if (ended.state && ended.tick) finish();
});
client.on("error", (error) => say({ event: "error", error: String(error) }));
process.stdin.on("end", () => setTimeout(finish, 20000)); // a run that never ended: what it had, 20 s on (not a judged margin)
process.stdin.resume();
