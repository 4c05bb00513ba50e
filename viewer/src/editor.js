// The editor panel (the seed's appendix A), shown only when `shatter view`
// serves a .shatter file: fragments, seed and strategy go to the
// server, which fractures the tree's root solid again while the page polls its
// progress, then the page loads the new tree. The server's API (cli/view.cpp):
//   POST api/fracture {fragments, seed, strategy} -> 202 {state: "running"} or 4xx {error}
//   GET  api/fracture -> {state: "idle" | "running" | "done" | "failed", leaves_done, fragments, generation, error}
//   GET  model.glb?generation=G -> the tree being shown, as a GLB

const POLL_MS = 150;

/** The message of a failed response: the server's {error} when it sent one, else the HTTP status. */
export async function errorOf(response) {
  try {
    const body = await response.json();
    if (body && typeof body.error === 'string') return body.error;
  } catch (e) {
    // not JSON: fall through to the status line
  }
  return `the server answered ${response.status} ${response.statusText}`.trim();
}

export class Editor {
  /**
   * `elements`: the panel's inputs and outputs; `onTree(generation)` loads the new tree and resolves when shown;
   * `showError(text)` puts a message on the page.
   */
  constructor(elements, onTree, showError) {
    this.e = elements;
    this.onTree = onTree;
    this.showError = showError;
    this.running = false;
    this.e.run.addEventListener('click', () => this.run());
  }

  /** Fills the inputs with the options the shown tree was built with (from api/session). */
  setOptions(options) {
    if (!options) return;
    if (options.fragments !== undefined) this.e.fragments.value = options.fragments;
    if (options.seed !== undefined) this.e.seed.value = options.seed;
    if (options.strategy) this.e.strategy.value = options.strategy;
  }

  status(text) { this.e.status.textContent = text; }

  async run() {
    if (this.running) return;
    const fragments = this.e.fragments.value.trim();
    const seed = this.e.seed.value.trim();
    if (!/^[0-9]+$/.test(fragments) || Number(fragments) < 1) {
      this.showError('Fragments must be a whole number of at least 1.');
      return;
    }
    if (!/^[0-9]+$/.test(seed)) {
      this.showError('The seed must be a whole number (decimal digits only).');
      return;
    }
    this.running = true;
    this.e.run.disabled = true;
    this.e.progress.hidden = false;
    this.e.progress.value = 0;
    this.status('Starting…');
    try {
      // Numbers go as strings: a seed may exceed JavaScript's exact integers (2^53).
      const response = await fetch('api/fracture', {
        method: 'POST',
        headers: { 'Content-Type': 'application/json' },
        body: JSON.stringify({ fragments, seed, strategy: this.e.strategy.value }),
      });
      if (!response.ok) throw new Error(await errorOf(response));
      const done = await this.poll();
      this.status('Loading the new tree…');
      await this.onTree(done.generation);
      this.status(`Fractured into ${done.leaves} fragments in ${done.seconds.toFixed(2)} s.`);
    } catch (error) {
      this.status('Failed.');
      this.showError(`Fracture failed: ${error.message}`);
    } finally {
      this.running = false;
      this.e.run.disabled = false;
      this.e.progress.hidden = true;
    }
  }

  // Polls api/fracture until the job ends; resolves with the final state, rejects with the server's error.
  async poll() {
    for (;;) {
      await new Promise((resolve) => setTimeout(resolve, POLL_MS));
      const response = await fetch('api/fracture', { cache: 'no-store' });
      if (!response.ok) throw new Error(await errorOf(response));
      const state = await response.json();
      if (state.state === 'failed') throw new Error(state.error || 'the server gave no reason');
      if (state.state === 'done') return state;
      if (state.state !== 'running') throw new Error(`unexpected job state '${state.state}'`);
      const fraction = state.fragments > 0 ? Math.min(state.leaves_done / state.fragments, 1) : 0;
      this.e.progress.value = fraction;
      this.status(`Fracturing: ${state.leaves_done} of ${state.fragments} fragments…`);
    }
  }
}
