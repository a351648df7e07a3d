// What arrives from the daemon, checked and kept: MeshInfo, the Model (parameters), Status, and
// the newest Frame not yet handed to the page. Runs in the worker, off the page's main thread.
//
// A message whose header, MeshInfo or Model breaks the spec throws a ProtocolError: the
// connection is closed and opened again. A Frame that does not fit (truncated, oversized,
// inconsistent counts, values that are not finite, bytes the codec refuses) is rejected alone:
// counted, its one-line reason kept, and the stream goes on with the next frame.
import {
  Encoding, MessageType, FrameFlags, FrameHeader, ProtocolError, SourceState, PROTOCOL_VERSION,
  readHeader, decodeMeshInfo, decodeStatus,
} from './protocol.js';
import { decodeModel, checkParameterBlock } from './model_message.js';
import { CompressedVertexDecoder } from './compressed_decoder.js';
import { RateMeter } from './rate_meter.js';

export class StreamReceiver {
  // listener: { onMeshInfo(meshInfo), onModel(model), onRejected(message) }
  constructor(listener) {
    this.listener = listener;
    this.meshInfo = null;
    this.model = null;
    this.compressed = null;
    this.header = new FrameHeader();
    this.pending = null;
    this.status = null;
    this.rate = new RateMeter();
    this.framesReceived = 0;
    this.framesSkipped = 0;
    this.framesWithoutKey = 0;
    this.framesRejected = 0;
    this.lastReceivedFrameNumber = -1;
    this.lastFrameArrivalMs = 0;
    this.frameNumbersWentBack = 0;
    this.arrivalLatencyMs = NaN;
  }

  // A new connection: the daemon sends MeshInfo (and the Model) again, and the rate window
  // starts over.
  onConnectionOpened() {
    this.meshInfo = null;
    this.model = null;
    this.compressed = null;
    this.pending = null;
    this.status = null;
    this.rate.reset();
  }

  onMessage(buffer, nowMs) {
    const view = new DataView(buffer);
    switch (readHeader(view, PROTOCOL_VERSION)) {
      case MessageType.MESH_INFO:
        this.acceptMeshInfo(decodeMeshInfo(view, PROTOCOL_VERSION));
        return;
      case MessageType.MODEL:
        this.acceptModel(view);
        return;
      case MessageType.FRAME:
        if (!this.meshInfo) throw new ProtocolError('Frame before MeshInfo');
        try {
          this.acceptFrame(view, buffer, nowMs);
        } catch (error) {
          if (!(error instanceof ProtocolError)) throw error;
          this.reject(error);
        }
        return;
      case MessageType.STATUS:
        this.status = decodeStatus(view, PROTOCOL_VERSION);
        return;
      default:
        throw new ProtocolError(`the daemon sent a message of type ${view.getUint16(6, true)}, which only subscribers send`);
    }
  }

  reject(error) {
    ++this.framesRejected;
    this.listener.onRejected(error.message);
  }

  acceptMeshInfo(info) {
    this.meshInfo = info;
    this.model = null;
    this.pending = null;
    this.compressed = info.encoding === Encoding.COMPRESSED ? new CompressedVertexDecoder(info.vertexCount, info.compressedOrder) : null;
    this.listener.onMeshInfo(info);
  }

  acceptModel(view) {
    const info = this.meshInfo;
    if (!info) throw new ProtocolError('Model before MeshInfo');
    if (info.encoding !== Encoding.PARAMETERS) throw new ProtocolError('a Model for a subscriber not served parameters');
    const model = decodeModel(view);
    if (model.vertexCount !== info.vertexCount) {
      throw new ProtocolError(`Model has ${model.vertexCount} vertices, MeshInfo said ${info.vertexCount}`);
    }
    if (model.partCount !== info.partCount) throw new ProtocolError(`Model has ${model.partCount} parts, MeshInfo said ${info.partCount}`);
    this.model = model;
    this.listener.onModel(model);
  }

  acceptFrame(view, buffer, nowMs) {
    const h = this.header;
    const info = this.meshInfo;
    h.read(view, PROTOCOL_VERSION);
    if (h.flags & FrameFlags.PARAMETERS) {
      if (!this.model) throw new ProtocolError(`Frame ${h.frameNumber} of parameters before the Model`);
      checkParameterBlock(view, h, this.model);
    } else if ((h.flags & FrameFlags.NO_POSITIONS) === 0 && h.vertexCount !== info.vertexCount) {
      throw new ProtocolError(`Frame ${h.frameNumber} has ${h.vertexCount} vertices, MeshInfo said ${info.vertexCount}`);
    }
    if ((h.flags & FrameFlags.MARKERS) !== 0 && h.markerCount !== info.markerCount) {
      throw new ProtocolError(`Frame ${h.frameNumber} has ${h.markerCount} markers, MeshInfo said ${info.markerCount}`);
    }
    if (h.flags & FrameFlags.COMPRESSED) {
      if (!this.compressed) throw new ProtocolError(`Frame ${h.frameNumber} is compressed, MeshInfo served ${info.encoding}`);
      if (!this.compressed.accept(view, h)) {
        ++this.framesWithoutKey;
        return;
      }
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

  // Whether a frame taken from takePending needs decodeCompressed before the page can draw it.
  isCompressed(buffer) {
    return this.compressed !== null && (new DataView(buffer).getUint32(16, true) & FrameFlags.COMPRESSED) !== 0;
  }

  // A compressed frame taken from takePending into 3V positions and normals (mesh order).
  // Returns whether normals were written. Throws ProtocolError on bytes the codec refuses.
  decodeCompressed(buffer, positions, normals) {
    const view = new DataView(buffer);
    this.header.read(view, PROTOCOL_VERSION);
    return this.compressed.decode(view, this.header, positions, normals);
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
