// The controls drawn over the picture: the store chooser (when the server has several), the
// isovalue slider over the store's histogram, and the view presets.
import { PRESET_NAMES } from './camera.js';

export class Panel {
  // elements: { store, storeRow, slider, isoInput, histogram, presets };
  // actions: { store(index), iso(value), preset(name) }
  constructor(elements, actions) {
    this.elements = elements;
    this.histogram = null;
    elements.store.addEventListener('change', () => actions.store(Number(elements.store.value)));
    elements.slider.addEventListener('input', () => actions.iso(Number(elements.slider.value)));
    elements.isoInput.addEventListener('change', () => {
      const { value, min, max } = elements.isoInput;
      if (value === '' || !Number.isFinite(Number(value))) return;
      actions.iso(Math.min(Math.max(Number(value), Number(min)), Number(max)));
    });
    for (const name of PRESET_NAMES) {
      const button = document.createElement('button');
      button.type = 'button';
      button.textContent = name;
      button.addEventListener('click', () => actions.preset(name));
      elements.presets.append(button);
    }
    // Redrawn whenever the canvas changes size: also when the panel is shown after starting
    // hidden (overlay=0, the 'o' key), when it had no size to draw at.
    new ResizeObserver(() => this.drawHistogram()).observe(elements.histogram);
  }

  setStores(stores) {
    const select = this.elements.store;
    select.replaceChildren(...stores.map((store, index) => new Option(store.name, String(index))));
    this.elements.storeRow.hidden = stores.length < 2;
  }

  // Shows one store: its value range on the slider and its histogram behind it.
  setStore(index, store) {
    const { store: select, slider, isoInput } = this.elements;
    select.value = String(index);
    for (const input of [slider, isoInput]) {
      input.min = String(store.valueMin);
      input.max = String(store.valueMax);
      input.step = 'any';
    }
    this.histogram = { ...store.histogram, valueMin: store.valueMin, valueMax: store.valueMax };
    this.drawHistogram();
  }

  // A follower's store, isovalue and view are its leader's: its controls are off.
  setEnabled(enabled) {
    const { store, slider, isoInput, presets } = this.elements;
    for (const input of [store, slider, isoInput, ...presets.querySelectorAll('button')]) input.disabled = !enabled;
  }

  setIso(value) {
    this.elements.slider.value = String(value);
    this.elements.isoInput.value = String(value);
  }

  // Bins on a log scale (counts span many decades: air dwarfs everything), placed on the
  // slider's value axis, which may be wider than the histogram's [lo, hi).
  drawHistogram() {
    const canvas = this.elements.histogram;
    const ratio = window.devicePixelRatio;
    canvas.width = Math.round(canvas.clientWidth * ratio);
    canvas.height = Math.round(canvas.clientHeight * ratio);
    const context = canvas.getContext('2d');
    context.clearRect(0, 0, canvas.width, canvas.height);
    if (!this.histogram) return;
    const { lo, hi, counts, valueMin, valueMax } = this.histogram;
    const span = valueMax - valueMin || 1;
    const binWidth = (hi - lo) / counts.length;
    const top = Math.log1p(Math.max(1, ...counts));
    context.fillStyle = 'rgba(226, 216, 194, 0.45)';
    // One outline over all bins, so narrow bins do not leave seams between them.
    const x = (value) => ((value - valueMin) / span) * canvas.width;
    const y = (n) => canvas.height * (1 - Math.log1p(n) / top);
    context.beginPath();
    context.moveTo(x(lo), canvas.height);
    counts.forEach((n, bin) => {
      context.lineTo(x(lo + bin * binWidth), y(n));
      context.lineTo(x(lo + (bin + 1) * binWidth), y(n));
    });
    context.lineTo(x(hi), canvas.height);
    context.closePath();
    context.fill();
  }
}
