// The receiving side of the stream, run in a worker: checks every message as it arrives (cheap
// header reads), keeps MeshInfo, Status and the counters, and holds only the newest Frame until
// the page asks for one. A frame replaced before the page asked is counted as skipped.
import {
  MessageType, FrameFlags, FrameHeader, ProtocolError, SourceState,
  readHeader, decodeMeshInfo, decodeStatus,
} from './protocol.js';
import { RateMeter } from './rate_meter.js';

export class StreamReceiver {
  // listener: { onMeshInfo(meshInfo) }
  constructor(listener) {
    this.listener = listener;
    this.meshInfo = null;
    this.header = new FrameHeader();
    this.pending = null;
    this.status = null;
    this.rate = new RateMeter();
    this.framesReceived = 0;
    this.framesSkipped = 0;
    this.lastReceivedFrameNumber = -1;
    this.lastFrameArrivalMs = 0;
    this.frameNumbersWentBack = 0;
  }

  // A new connection: the daemon sends MeshInfo again, and the rate window starts over.
  onConnectionOpened() {
    this.meshInfo = null;
    this.pending = null;
    this.status = null;
    this.rate.reset();
  }

  onMessage(buffer, nowMs) {
    const view = new DataView(buffer);
    switch (readHeader(view)) {
      case MessageType.MESH_INFO:
        this.meshInfo = decodeMeshInfo(view);
        this.pending = null;
        this.listener.onMeshInfo(this.meshInfo);
        return;
      case MessageType.FRAME:
        this.acceptFrame(view, buffer, nowMs);
        return;
      case MessageType.STATUS:
        this.status = decodeStatus(view);
        return;
      default:
        throw new ProtocolError('the daemon sent a Hello');
    }
  }

  acceptFrame(view, buffer, nowMs) {
    if (!this.meshInfo) throw new ProtocolError('Frame before MeshInfo');
    const h = this.header;
    h.read(view);
    if ((h.flags & FrameFlags.NO_POSITIONS) === 0 && h.vertexCount !== this.meshInfo.vertexCount) {
      throw new ProtocolError(`Frame ${h.frameNumber} has ${h.vertexCount} vertices, MeshInfo said ${this.meshInfo.vertexCount}`);
    }
    if ((h.flags & FrameFlags.MARKERS) !== 0 && h.markerCount !== this.meshInfo.markerCount) {
      throw new ProtocolError(`Frame ${h.frameNumber} has ${h.markerCount} markers, MeshInfo said ${this.meshInfo.markerCount}`);
    }
    if (h.frameNumber <= this.lastReceivedFrameNumber) ++this.frameNumbersWentBack;
    ++this.framesReceived;
    this.lastReceivedFrameNumber = h.frameNumber;
    this.lastFrameArrivalMs = nowMs;
    // Daemon publish -> arrival here: the network and the browser's own queues, before the page.
    this.arrivalLatencyMs = nowMs - h.publishTimeNs / 1e6;
    this.rate.add(h.frameNumber, nowMs);
    if (this.pending !== null) ++this.framesSkipped;
    this.pending = buffer;
  }

  // The newest frame not yet handed out, or null.
  takePending() {
    const buffer = this.pending;
    this.pending = null;
    return buffer;
  }

  // True when the source is gone: the daemon says so, or frames stopped for a second.
  sourceGone(nowMs) {
    if (this.status && (this.status.state === SourceState.DISCONNECTED || this.status.state === SourceState.FINISHED)) return true;
    return this.framesReceived > 0 && nowMs - this.lastFrameArrivalMs > 1000;
  }

  // The rate the daemon reports (Status, else MeshInfo), 0 when unknown.
  announcedRateHz() {
    if (this.status && this.status.sourceRateHz > 0) return this.status.sourceRateHz;
    return this.meshInfo ? this.meshInfo.sourceRateHz : 0;
  }
}
