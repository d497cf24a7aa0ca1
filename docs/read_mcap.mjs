// Read a flexdigit MCAP recording with @mcap/core (the TypeScript implementation, not flexdigit's code):
//   npm install @mcap/core && node docs/read_mcap.mjs run.mcap
// Prints the channels, schemas, metadata, message counts and whether log times only grow on each topic; the stream
// reader reads a killed recording to its last closed chunk, the indexed reader needs the summary of a closed one.
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { readFileSync } from "node:fs";

const buf = readFileSync(process.argv[2]);
const stream = new McapStreamReader({ validateCrcs: true });
stream.append(new Uint8Array(buf));
const text = new TextDecoder();
const schemas = {}, channels = {}, metadata = {}, counts = {}, lastTime = {};
let backwards = 0, notJson = 0, record;
try {
  while ((record = stream.nextRecord())) {
    if (record.type === "Schema") schemas[record.id] = [record.name, record.encoding];
    else if (record.type === "Channel") channels[record.id] = [record.topic, record.messageEncoding, record.schemaId];
    else if (record.type === "Metadata") metadata[record.name] = Object.fromEntries(record.metadata);
    else if (record.type === "Message") {
      const topic = channels[record.channelId][0];
      counts[topic] = (counts[topic] || 0) + 1;
      if (lastTime[topic] !== undefined && record.logTime < lastTime[topic]) backwards++;
      lastTime[topic] = record.logTime;
      try { JSON.parse(text.decode(record.data)); } catch { notJson++; }
    }
  }
} catch (e) { console.log("stream reader stopped (a killed recording's torn end):", e.message); }
console.log(JSON.stringify({
  complete: stream.done(), counts, backwards, notJson,
  channels: Object.values(channels).map(([topic, enc, id]) => [topic, enc, ...schemas[id]]),
  metadata: Object.fromEntries(Object.entries(metadata).map(([k, v]) => [k, Object.keys(v)])),
  stop: metadata["flexdigit.stop"] ?? null,
}, null, 1));
try {
  const readable = { size: async () => BigInt(buf.length), read: async (o, n) => buf.subarray(Number(o), Number(o + n)) };
  const indexed = await McapIndexedReader.Initialize({ readable });
  let n = 0;
  for await (const _ of indexed.readMessages()) n++;
  console.log(`indexed reader: ${n} messages in ${indexed.chunkIndexes.length} chunks`);
} catch (e) { console.log("indexed reader: no summary (a killed recording):", e.message); }
