// Source rate from the frames' arrival: frame numbers advanced per second of browser clock over
// the last few seconds. Counting frame numbers (not messages) keeps the estimate right when this
// subscriber or the daemon drops frames, and a window of seconds (not frames) evens out bursts
// when the page falls behind for a moment. A ring buffer allocated once; nothing per sample.
const CAPACITY = 2048;

export class RateMeter {
  constructor(windowMs = 3000) {
    this.windowMs = windowMs;
    this.times = new Float64Array(CAPACITY);
    this.frames = new Float64Array(CAPACITY);
    this.reset();
  }

  reset() {
    this.count = 0;
    this.next = 0;
  }

  newestIndex() {
    return (this.next + CAPACITY - 1) % CAPACITY;
  }

  // A frame number going backwards (a looped recording, a restarted source) starts a new window.
  add(frameNumber, nowMs) {
    if (this.count > 0 && frameNumber <= this.frames[this.newestIndex()]) this.reset();
    this.times[this.next] = nowMs;
    this.frames[this.next] = frameNumber;
    this.next = (this.next + 1) % CAPACITY;
    if (this.count < CAPACITY) ++this.count;
    // Forget samples older than the window, keeping at least two.
    while (this.count > 2 && nowMs - this.times[(this.next + CAPACITY - this.count) % CAPACITY] > this.windowMs) --this.count;
  }

  // Hz, or 0 while fewer than two frames are in the window.
  rateHz() {
    if (this.count < 2) return 0;
    const newest = this.newestIndex();
    const oldest = (this.next + CAPACITY - this.count) % CAPACITY;
    const seconds = (this.times[newest] - this.times[oldest]) / 1000;
    return seconds > 0 ? (this.frames[newest] - this.frames[oldest]) / seconds : 0;
  }
}
