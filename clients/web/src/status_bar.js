// The status bar and the banner. Updated a few times a second, not per frame: text layout is the
// costly part of a DOM update and nobody reads faster than that.
const byId = (id) => document.getElementById(id);

function setText(element, text) {
  if (element.textContent !== text) element.textContent = text;
}

export class StatusBar {
  constructor() {
    this.fields = {
      frame: byId('status-frame'),
      rate: byId('status-rate'),
      latency: byId('status-latency'),
      dropped: byId('status-dropped'),
      filled: byId('status-filled'),
      source: byId('status-source'),
      encoding: byId('status-encoding'),
      error: byId('status-error'),
    };
    this.banner = byId('banner');
  }

  // s: a snapshot of the viewer's state (see main.js publishStatus).
  show(s) {
    setText(this.fields.frame, s.lastFrameNumber >= 0 ? String(s.lastFrameNumber) : '–');
    const announced = s.announcedRateHz > 0 ? ` (daemon ${s.announcedRateHz.toFixed(1)})` : '';
    setText(this.fields.rate, s.sourceRateHz > 0 ? `${s.sourceRateHz.toFixed(1)} Hz${announced}` : `– Hz${announced}`);
    this.fields.rate.dataset.hz = s.sourceRateHz.toFixed(3);
    setText(this.fields.latency, Number.isFinite(s.latencyMs) ? `${s.latencyMs.toFixed(1)} ms` : '–');
    setText(this.fields.dropped, `pipeline ${s.framesDroppedPipeline} · this viewer ${s.framesDroppedSubscriber} · skipped by page ${s.framesSkipped}`);
    setText(this.fields.filled, s.markerCount > 0 ? `${s.markersFilled} / ${s.markerCount} (relabelled ${s.markersRelabelled})` : '–');
    setText(this.fields.source, s.sourceStateName + (s.sourceDetail ? `: ${s.sourceDetail}` : ''));
    setText(this.fields.encoding, s.encodingName);
    // The stream's last error, one line, shown until the page is reloaded: bad input is rare
    // and a user should see that it happened.
    this.fields.error.parentElement.hidden = s.errorText === '';
    setText(this.fields.error, s.errorText);
  }

  // kind: '' hides the banner; 'source' or 'connection' or 'error' show it with that style.
  showBanner(kind, text) {
    this.banner.hidden = kind === '';
    this.banner.dataset.kind = kind;
    setText(this.banner, text);
  }
}
