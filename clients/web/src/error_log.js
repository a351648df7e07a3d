// The stream's errors for the status bar and the console: the last one as one line, how many
// there were, and at most one console line a second (a daemon sending bad frames at 120 Hz would
// otherwise flood the console and slow the page).
const LOG_INTERVAL_MS = 1000;

export class ErrorLog {
  // log(line): where a line goes (console.error in the page and the worker).
  constructor(log) {
    this.log = log;
    this.last = '';
    this.count = 0;
    this.unlogged = 0;
    this.lastLoggedMs = -Infinity;
  }

  add(message, nowMs) {
    this.last = String(message).split('\n')[0];
    ++this.count;
    if (nowMs - this.lastLoggedMs < LOG_INTERVAL_MS) {
      ++this.unlogged;
      return;
    }
    const more = this.unlogged > 0 ? ` (and ${this.unlogged} more since the last line)` : '';
    this.log(`${this.last}${more}`);
    this.unlogged = 0;
    this.lastLoggedMs = nowMs;
  }
}
