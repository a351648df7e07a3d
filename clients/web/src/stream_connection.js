// The WebSocket to the daemon's /stream: sends a version 2 Hello first, hands each binary
// message to the listener, acknowledges each Frame when the Hello asked for pacing, and
// reconnects with exponential backoff whenever the socket closes.
import { encodeAck, encodeHello, MessageType, ProtocolError, readHeader, Wants } from './protocol.js';
import { unpackMessage } from './packed_message.js';

const isPacked = (data) => data.byteLength >= 8 && new DataView(data).getUint16(6, true) === MessageType.PACKED;

export const ConnectionState = Object.freeze({ CONNECTING: 'connecting', OPEN: 'open', CLOSED: 'closed' });

const FIRST_RETRY_MS = 250;
const MAX_RETRY_MS = 5000;

export class StreamConnection {
  // hello: { wants, encoding, subject, token } (see encodeHello).
  // listener: { onOpen(), onMessage(ArrayBuffer), onProtocolError(error), onClose(reason, retryInMs) }
  constructor(url, hello, listener) {
    this.url = url;
    this.paced = (hello.wants & Wants.PACED) !== 0;
    // Packed MeshInfo and Model only where the platform inflates (DecompressionStream).
    const packed = (hello.wants & Wants.PACKED) !== 0 && typeof DecompressionStream === 'function';
    this.hello = encodeHello(packed ? hello.wants : hello.wants & ~Wants.PACKED, hello);
    this.packed = packed;
    this.listener = listener;
    this.state = ConnectionState.CLOSED;
    this.retryMs = FIRST_RETRY_MS;
    this.reconnects = 0;
    this.socket = null;
    this.retryTimer = 0;
    this.waiting = 0; // messages held behind a Packed one being inflated
    this.queue = Promise.resolve();
  }

  async unpack(data) {
    readHeader(new DataView(data));
    if (!this.packed) throw new ProtocolError('the daemon sent a Packed message, which this page did not ask for');
    return unpackMessage(data);
  }

  // One plain message to the listener (and its Ack when paced).
  deliver(socket, data) {
    try {
      // Read before the listener runs: it may transfer the buffer to the page (detaching it).
      let ack = null;
      if (this.paced && data.byteLength >= 16) {
        const view = new DataView(data);
        if (view.getUint16(6, true) === MessageType.FRAME) ack = encodeAck(view.getUint32(12, true));
      }
      this.listener.onMessage(data);
      // Acked on arrival: the window then bounds what waits in the sockets, and the worker
      // keeps only the newest frame for the page.
      if (ack) socket.send(ack);
    } catch (error) {
      this.fail(socket, error);
    }
  }

  fail(socket, error) {
    if (!(error instanceof ProtocolError)) throw error;
    if (this.socket !== socket) return;
    this.listener.onProtocolError(error);
    this.lastError = error.message;
    this.abort(error);
  }

  start() {
    this.open();
  }

  // A good message proves the link works: the next failure starts the backoff from the bottom.
  confirmHealthy() {
    this.retryMs = FIRST_RETRY_MS;
  }

  // Closes on a protocol violation, as the spec asks of a receiver; the backoff then reconnects.
  abort(error) {
    if (this.socket) this.socket.close(4000, String(error.message).slice(0, 120));
  }

  open() {
    this.state = ConnectionState.CONNECTING;
    let socket;
    try {
      socket = new WebSocket(this.url);
    } catch (error) {
      this.scheduleRetry(`cannot open ${this.url}: ${error.message}`);
      return;
    }
    socket.binaryType = 'arraybuffer';
    this.socket = socket;
    socket.onopen = () => {
      this.state = ConnectionState.OPEN;
      socket.send(this.hello);
      this.listener.onOpen();
    };
    socket.onmessage = (event) => {
      if (!(event.data instanceof ArrayBuffer)) {
        this.abort(new ProtocolError('text message on a binary protocol'));
        return;
      }
      // A Packed message is inflated asynchronously: it and every message behind it wait their
      // turn, so the listener still gets them in order.
      if (this.waiting === 0 && !isPacked(event.data)) {
        this.deliver(socket, event.data);
        return;
      }
      const data = event.data;
      ++this.waiting;
      this.queue = this.queue
        .then(async () => {
          if (this.socket !== socket) return; // closed meanwhile: a new connection starts afresh
          this.deliver(socket, isPacked(data) ? await this.unpack(data) : data);
        })
        // A fault that is not the daemon's (a bug here) ends this connection too: the messages
        // behind it must not be read out of order.
        .catch((error) => this.fail(socket, error instanceof ProtocolError ? error : new ProtocolError(`unpacking: ${error}`)))
        .finally(() => { --this.waiting; });
    };
    socket.onclose = (event) => {
      if (this.socket !== socket) return;
      this.socket = null;
      const reason = this.lastError || event.reason || `code ${event.code}`;
      this.lastError = '';
      this.scheduleRetry(reason);
    };
    // onerror is always followed by onclose, which does the work.
  }

  scheduleRetry(reason) {
    this.state = ConnectionState.CLOSED;
    const delay = this.retryMs;
    this.retryMs = Math.min(MAX_RETRY_MS, this.retryMs * 2);
    this.listener.onClose(reason, delay);
    clearTimeout(this.retryTimer);
    this.retryTimer = setTimeout(() => {
      ++this.reconnects;
      this.open();
    }, delay);
  }
}
