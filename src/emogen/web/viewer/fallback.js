// Without WebGL 2: each slot shows a PNG rendered by the server (emogen.render), fetched from a
// URL template with {weights} (comma-separated, the model's shape order), {size} and {i}.
export class ImageGrid {
  constructor(slots, { template, size, shapeNames }) {
    this.slots = slots;
    this.template = template;
    this.size = size;
    this.shapeNames = shapeNames ?? null;
    this.images = slots.map((slot) => {
      const img = document.createElement('img');
      img.alt = 'face';
      img.width = size;
      img.height = size;
      slot.appendChild(img);
      return img;
    });
  }

  url(i, weights) {
    const vector = Array.isArray(weights) || ArrayBuffer.isView(weights)
      ? Array.from(weights, Number)
      : (this.shapeNames ?? Object.keys(weights)).map((n) => Number(weights[n] ?? 0));
    const text = vector.map((x) => +x.toFixed(4)).join(',');
    return this.template
      .replaceAll('{weights}', encodeURIComponent(text))
      .replaceAll('{size}', String(this.size))
      .replaceAll('{i}', String(i));
  }

  /** Resolves when every image has loaded (or failed: the slot shows its alt text). */
  setFaces(weights) {
    const n = Math.min(weights.length, this.images.length);
    const loads = [];
    for (let i = 0; i < n; i++) {
      const img = this.images[i];
      loads.push(
        new Promise((resolve) => {
          img.onload = () => resolve(true);
          img.onerror = () => resolve(false);
          img.src = this.url(i, weights[i]);
        }),
      );
    }
    return Promise.all(loads);
  }
}
