// A second subscriber to the daemon, from node over a real WebSocket (the ws package). Asking for
// float vertices and normals (the default), it holds the daemon's own buffers, against which the
// page's are compared: the last frames, by frame number and the daemon's receive time. It also
// counts the bytes of what arrives, for any encoding.
import { createRequire } from 'node:module';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const repoRoot = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../../..');
const requireWeb = createRequire(path.join(repoRoot, 'clients/web/package.json'));
const protocol = await import(path.join(repoRoot, 'clients/web/src/protocol.js'));

export class ReferenceSubscriber {
  // keep: how many recent frames to hold (a float frame with normals is 1.3 MB on the demo body):
  // two seconds, as a page on a loaded machine draws a frame 0.2-1 s after the daemon got it.
  constructor(url, { keep = 240, encoding = protocol.Encoding.FLOAT, wants = protocol.Wants.NORMALS } = {}) {
    const WebSocket = requireWeb('ws');
    this.keep = keep;
    this.frames = new Map(); // "frame number@receive time" -> ArrayBuffer
    this.meshInfo = null;
    this.errors = [];
    this.modelBytes = 0;
    this.frameBytes = []; // of every Frame received
    this.socket = new WebSocket(url);
    this.socket.binaryType = 'arraybuffer';
    this.opened = new Promise((resolve, reject) => {
      this.socket.on('open', resolve);
      this.socket.on('error', reject);
    });
    this.socket.on('open', () => {
      const hello = protocol.encodeHello(wants, { encoding });
      this.socket.send(Buffer.from(hello));
    });
    this.socket.on('message', (data) => this.onMessage(data));
  }

  onMessage(buffer) {
    try {
      const view = new DataView(buffer);
      const type = protocol.readHeader(view);
      if (type === protocol.MessageType.MESH_INFO) {
        this.meshInfo = protocol.decodeMeshInfo(view);
      } else if (type === protocol.MessageType.MODEL) {
        this.modelBytes = buffer.byteLength;
      } else if (type === protocol.MessageType.FRAME) {
        this.frameBytes.push(buffer.byteLength);
        if (this.meshInfo.encoding !== protocol.Encoding.FLOAT) return;
        const header = new protocol.FrameHeader();
        header.read(view);
        const key = `${header.frameNumber}@${header.receiveTimeNs}`;
        this.frames.set(key, buffer);
        if (this.frames.size > this.keep) this.frames.delete(this.frames.keys().next().value);
      }
    } catch (error) {
      this.errors.push(error.message);
    }
  }

  // The keys of the frames held: "frame number@daemon receive time", which tells apart the
  // frames of a looped replay that share a number.
  keys() {
    return [...this.frames.keys()];
  }

  // { positions, normals } (Float32Array, 3 per vertex) of a frame still held, else null.
  frame(key) {
    const buffer = this.frames.get(key);
    if (!buffer || !this.meshInfo) return null;
    const view = new DataView(buffer);
    const header = new protocol.FrameHeader();
    header.read(view);
    const V = this.meshInfo.vertexCount;
    const out = { positions: new Float32Array(3 * V), normals: new Float32Array(3 * V), markers: new Float32Array(0), markerStatus: new Uint8Array(0) };
    protocol.decodeFrameArrays(view, header, out);
    return out;
  }

  // The frame of `key` once it is held: the page may draw a frame before this subscriber has
  // read it (node busy on a loaded machine), so it is waited for; null as soon as a newer frame
  // is held without it.
  async waitForFrame(key, timeoutMs = 2000) {
    const deadline = Date.now() + timeoutMs;
    const receiveTime = (k) => BigInt(k.split('@')[1]);
    for (;;) {
      const frame = this.frame(key);
      if (frame !== null || Date.now() >= deadline) return frame;
      // Frames arrive in order: once a newer one is held, this one was skipped for this
      // subscriber (the daemon's newest-wins queue on a loaded machine) or has gone already.
      const newest = [...this.frames.keys()].pop();
      if (newest !== undefined && receiveTime(newest) > receiveTime(key)) return null;
      await new Promise((resolve) => setTimeout(resolve, 20));
    }
  }

  close() {
    this.socket.close();
  }
}
