// Follow mode (docs/protocol.md, "Follow mode"): whether this page leads its own frames or
// follows another viewer's, the link that others open to follow it, and the hand-over of
// control to a follower.
const ID = /^[0-9a-f]{8}$/;

export class Follow {
  // elements: { state, link, copy, handOver }; wanted: the session ?follow= names, or null;
  // onHandOver(): the user gives control to the first follower.
  constructor(elements, wanted, onHandOver) {
    if (wanted !== null && !ID.test(wanted)) throw new Error(`URL parameter follow=${wanted} is not a session id (8 hex digits)`);
    this.elements = elements;
    this.session = null;
    this.leader = null;
    this.followers = [];
    this.waiting = wanted !== null; // asked to follow, no answer yet
    elements.copy.addEventListener('click', () => {
      elements.link.select();
      navigator.clipboard?.writeText(elements.link.value).catch(() => {});
    });
    elements.handOver.addEventListener('click', () => onHandOver());
  }

  // Draws the leader's VIEWs only; a follower (or one waiting to be) sends none.
  get following() {
    return this.waiting || (this.leader !== null && this.leader !== this.session);
  }

  hello(session) {
    this.session = session;
    if (!this.waiting) this.leader = session;
    this.render();
  }

  // A `role` message: who leads this page's group now, and who follows.
  role({ leader, followers }) {
    this.waiting = false;
    this.leader = leader;
    this.followers = followers;
    this.render();
  }

  // The server could not make this page follow (the session is gone): it leads its own.
  refused() {
    this.waiting = false;
    this.leader = this.session;
    this.render();
  }

  // This page's URL, following this page's session (the token kept, if the URL had it).
  link() {
    const url = new URL(window.location.href);
    url.searchParams.set('follow', this.leader ?? this.session);
    return url.toString();
  }

  snapshot() {
    return { session: this.session, leader: this.leader, followers: [...this.followers], following: this.following };
  }

  render() {
    const { state, link, handOver } = this.elements;
    const n = this.followers.length;
    if (this.waiting) state.textContent = 'joining…';
    else if (this.following) state.textContent = `following ${this.leader}`;
    else state.textContent = n === 0 ? 'leading · no followers' : `leading · ${n} follower${n === 1 ? '' : 's'}`;
    link.value = this.session === null ? '' : this.link();
    handOver.hidden = this.following || n === 0;
  }
}
