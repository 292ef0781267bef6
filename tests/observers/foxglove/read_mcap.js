// Foxglove's own MCAP reader (@mcap/core, TypeScript; zstd by fzstd) on a file the executive wrote.
// node read_mcap.js FILE [TIME_NS]: prints one JSON object: the header, channels and schemas, statistics, the chunks'
// compression, each topic's messages (CRCs checked) with the first one parsed, the metadata; with TIME_NS, the
// /tree/tick messages read through the index from that log time for one second.
const fs = require("fs");
const { McapIndexedReader } = require("@mcap/core");
const { decompress } = require("fzstd");

async function main() {
  const [path, at] = process.argv.slice(2);
  const fd = fs.openSync(path, "r");
  const readable = {
    size: async () => BigInt(fs.fstatSync(fd).size),
    read: async (offset, length) => {
      const buffer = Buffer.alloc(Number(length));
      fs.readSync(fd, buffer, 0, Number(length), Number(offset));
      return buffer;
    },
  };
  const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers: { zstd: (data) => decompress(data) } });
  const channels = {};
  for (const channel of reader.channelsById.values()) {
    const schema = reader.schemasById.get(channel.schemaId);
    channels[channel.topic] = { encoding: channel.messageEncoding, schema: schema.name, schemaEncoding: schema.encoding, count: 0 };
  }
  let last = -1n;
  for await (const message of reader.readMessages({ validateCrcs: true })) {
    const channel = channels[reader.channelsById.get(message.channelId).topic];
    channel.count += 1;
    channel.first ??= JSON.parse(new TextDecoder().decode(message.data));
    if (message.logTime < last) throw new Error("messages out of log-time order");
    last = message.logTime;
  }
  const metadata = [];
  for await (const record of reader.readMetadata()) metadata.push(record.name);
  const seek = [];
  if (at !== undefined) {
    const start = BigInt(at);
    for await (const message of reader.readMessages({ topics: ["/tree/tick"], startTime: start, endTime: start + 999999999n })) {
      seek.push(JSON.parse(new TextDecoder().decode(message.data)).tick);
    }
  }
  const compression = [...new Set(reader.chunkIndexes.map((c) => c.compression))];
  const messageCount = Number(reader.statistics.messageCount);
  console.log(JSON.stringify({ library: reader.header.library, channels, messageCount, compression, metadata, seek }));
}

main().catch((error) => {
  console.error(String(error.stack || error));
  process.exit(1);
});
