// A stand-in for the daemon that a test scripts message by message: serves the built page over
// HTTP and speaks WebSocket at /stream (the ws package), on 127.0.0.1 and a free port. Each
// connection is handed to the test once its first message (the Hello) has arrived.
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import { createRequire } from 'node:module';
import { repoRoot } from './fixtures.mjs';

const requireWeb = createRequire(path.join(repoRoot, 'clients/web/package.json'));
const CONTENT_TYPES = { '.html': 'text/html; charset=utf-8', '.js': 'text/javascript; charset=utf-8' };

export class ScriptedServer {
  constructor(webRoot) {
    const { WebSocketServer } = requireWeb('ws');
    this.webRoot = webRoot;
    this.waiting = [];
    this.arrived = [];
    this.sockets = new Set();
    this.http = http.createServer((request, response) => this.serveFile(request, response));
    this.webSockets = new WebSocketServer({ noServer: true });
    this.http.on('upgrade', (request, socket, head) => {
      if (new URL(request.url, 'http://x').pathname !== '/stream') {
        socket.destroy();
        return;
      }
      this.webSockets.handleUpgrade(request, socket, head, (ws) => this.accept(ws));
    });
  }

  async listen() {
    await new Promise((resolve) => this.http.listen(0, '127.0.0.1', resolve));
    return this.http.address().port;
  }

  serveFile(request, response) {
    const name = new URL(request.url, 'http://x').pathname.replace(/^\/$/, '/index.html');
    const file = path.join(this.webRoot, path.basename(name));
    if (!fs.existsSync(file)) {
      response.writeHead(404).end();
      return;
    }
    response.writeHead(200, { 'content-type': CONTENT_TYPES[path.extname(file)] || 'application/octet-stream' });
    response.end(fs.readFileSync(file));
  }

  accept(ws) {
    this.sockets.add(ws);
    ws.on('close', () => this.sockets.delete(ws));
    ws.once('message', (data) => {
      const hello = data.buffer.slice(data.byteOffset, data.byteOffset + data.byteLength);
      const connection = { ws, hello, send: (buffer) => ws.send(Buffer.from(buffer)) };
      const waiter = this.waiting.shift();
      if (waiter) waiter(connection);
      else this.arrived.push(connection);
    });
  }

  // The next connection whose Hello arrived, within timeoutMs.
  nextConnection(timeoutMs = 20000) {
    if (this.arrived.length > 0) return Promise.resolve(this.arrived.shift());
    return new Promise((resolve, reject) => {
      const timer = setTimeout(() => reject(new Error(`no connection to the scripted server within ${timeoutMs} ms`)), timeoutMs);
      this.waiting.push((connection) => {
        clearTimeout(timer);
        resolve(connection);
      });
    });
  }

  async close() {
    for (const ws of this.sockets) ws.terminate();
    await new Promise((resolve) => this.webSockets.close(resolve));
    await new Promise((resolve) => this.http.close(resolve));
  }
}
