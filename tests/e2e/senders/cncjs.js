#!/usr/bin/env node
// inkstep end-to-end checks with a real sender: cncjs 1.11.5 (npm), driven through its
// socket.io API as its web UI drives it, with the board's serial port opened by path.
//
// Usage: node cncjs.js PORT REPO_ROOT GROUP
//   GROUP "streams": bench/star.nc and a program of many short segments (any speed);
//   GROUP "timing":  the %wait macro and pause/resume/stop, whose outcome depends on
//                    cncjs's real-time polling (run the board at real time).
// Every check asserts the exact end position and that no `error:` or `ALARM` line came.
// Each check runs on its own; exits 1 if any failed.
'use strict';

const { spawn } = require('child_process');
const fs = require('fs');
const net = require('net');
const os = require('os');
const path = require('path');
const io = require('socket.io-client');
const jwt = require('jsonwebtoken');

const [PORT, ROOT, GROUP] = process.argv.slice(2);
const SECRET = 'inkstep-e2e';

class Fail extends Error {}
function check(cond, msg) {
  if (!cond) throw new Fail(msg);
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// Positions as integer thousandths of a mm, from the controller's three-decimal text.
const milli = (s) => Math.round(Number(s) * 1000);
const fmt = (p) => `${(p[0] / 1000).toFixed(3)},${(p[1] / 1000).toFixed(3)}`;

function freePort() {
  return new Promise((resolve, reject) => {
    const srv = net.createServer();
    srv.listen(0, '127.0.0.1', () => {
      const { port } = srv.address();
      srv.close(() => resolve(port));
    });
    srv.on('error', reject);
  });
}

// cncjs's server, as `cncjs -p PORT -c CONFIG` runs it for a user.
async function startCncjs(dir) {
  const port = await freePort();
  const config = path.join(dir, 'cncrc.json');
  fs.writeFileSync(config, JSON.stringify({ secret: SECRET }));
  const bin = require.resolve('cncjs/bin/cncjs');
  const log = fs.openSync(path.join(dir, 'cncjs.log'), 'w');
  const child = spawn(process.execPath, [bin, '-p', String(port), '-H', '127.0.0.1', '-c', config], {
    stdio: ['ignore', log, log],
  });
  for (let i = 0; i < 300; i++) {
    if (child.exitCode !== null) break;
    if (fs.readFileSync(path.join(dir, 'cncjs.log'), 'utf8').includes('Starting the server')) {
      return { child, url: `http://127.0.0.1:${port}` };
    }
    await sleep(100);
  }
  child.kill();
  throw new Fail('cncjs did not start:\n' + fs.readFileSync(path.join(dir, 'cncjs.log'), 'utf8'));
}

// One socket.io client: what cncjs's web UI sees of the board.
class Client {
  constructor(url) {
    const token = jwt.sign({ id: '', name: 'inkstep-e2e' }, SECRET, { expiresIn: '1h' });
    this.socket = io.connect(url, { query: 'token=' + token, transports: ['websocket'] });
    this.reads = []; // every line cncjs shows in its console
    this.state = null; // the last controller state (cncjs's parse of `?`)
    this.workflow = 'idle';
    this.waiters = [];
    this.socket.on('serialport:read', (line) => {
      this.reads.push(line);
      this.wake();
    });
    this.socket.on('controller:state', (type, state) => {
      this.state = state;
      this.wake();
    });
    this.socket.on('workflow:state', (w) => {
      this.workflow = w;
      this.wake();
    });
    this.socket.on('sender:status', (s) => {
      this.sender = s;
      this.wake();
    });
  }

  wake() {
    for (const w of this.waiters.splice(0)) w();
  }

  // Resolves when cond() holds; fails after `ms` with `what`.
  async until(cond, ms, what) {
    const deadline = Date.now() + ms;
    while (!cond()) {
      const left = deadline - Date.now();
      if (left <= 0) throw new Fail(`timed out after ${ms} ms waiting for ${what}; ${this.describe()}`);
      await new Promise((r) => {
        const t = setTimeout(r, Math.min(left, 100));
        this.waiters.push(() => {
          clearTimeout(t);
          r();
        });
      });
    }
  }

  describe() {
    const s = this.state && this.state.status;
    const pos = s ? `${s.activeState} at ${s.mpos.x},${s.mpos.y}` : 'no state';
    return `state ${pos}, workflow ${this.workflow}, last lines: ${JSON.stringify(this.reads.slice(-5))}`;
  }

  emit(...args) {
    return new Promise((resolve, reject) =>
      this.socket.emit(...args, (err, data) => (err ? reject(new Fail(String(err))) : resolve(data)))
    );
  }

  command(...args) {
    this.socket.emit('command', PORT, ...args);
  }

  status() {
    return this.state && this.state.status;
  }

  mpos() {
    const s = this.status();
    return [milli(s.mpos.x), milli(s.mpos.y)];
  }

  problems(from) {
    return this.reads.slice(from).filter((l) => /^(error|ALARM)/.test(l));
  }

  async open() {
    await this.until(() => this.socket.connected, 20000, 'the socket.io connection');
    await this.emit('open', PORT, { controllerType: 'Grbl', baudrate: 115200 });
    // Ready once cncjs has parsed a status report.
    await this.until(() => this.status() && this.status().activeState === 'Idle', 20000, 'Idle after opening');
  }

  // Loads `text` as a G-code program and starts it, as the UI's "Run" button does.
  async start(name, text) {
    await this.emit('command', PORT, 'gcode:load', name, text);
    this.command('gcode:start');
    await this.until(() => this.workflow === 'running', 5000, 'the workflow to run');
  }

  // Waits until cncjs ends the job itself (all lines answered, then the machine idle).
  async finish(ms) {
    await this.until(() => this.workflow === 'idle', ms, 'the end of the job');
    await this.until(() => this.status().activeState === 'Idle', 5000, 'Idle');
  }

  // Runs a whole program and returns its end position and the lines answered.
  async run(name, text, ms) {
    const from = this.reads.length;
    const t0 = Date.now();
    await this.start(name, text);
    await this.finish(ms);
    const bad = this.problems(from);
    check(bad.length === 0, `${name}: ${bad.join(' | ')}`);
    const sent = this.sender;
    check(sent && sent.received === sent.total, `${name}: ${sent && sent.received} of ${sent && sent.total} lines answered`);
    return { end: this.mpos(), lines: sent.total, seconds: (Date.now() - t0) / 1000 };
  }
}

function readProgram(name) {
  return fs.readFileSync(path.join(ROOT, name), 'utf8');
}

// A program's expected end, from its first line: `(... ends at X95.000 Y5.000)`.
function expectedEnd(text) {
  const m = /ends at X(-?[\d.]+) Y(-?[\d.]+)/.exec(text.split('\n')[0]);
  check(m, 'the program does not say where it ends');
  return [milli(m[1]), milli(m[2])];
}

async function starStream(c) {
  const star = await c.run('star.nc', readProgram('bench/star.nc'), 120000);
  check(star.end[0] === 0 && star.end[1] === 0, `star.nc ended at ${fmt(star.end)}, not 0,0`);
  console.log(`  star.nc: ${star.lines} lines answered, no error, ended ${fmt(star.end)} (${star.seconds.toFixed(1)} s)`);
}

async function segmentStream(c) {
  const text = fs.readFileSync(path.join(__dirname, 'segments.nc'), 'utf8');
  const want = expectedEnd(text);
  const r = await c.run('segments.nc', text, 300000);
  check(r.end[0] === want[0] && r.end[1] === want[1], `segments.nc ended at ${fmt(r.end)}, not ${fmt(want)}`);
  console.log(`  segments.nc: ${r.lines} lines answered, no error, ended ${fmt(r.end)} (${r.seconds.toFixed(1)} s)`);
}

async function waitMacro(c) {
  // %wait: cncjs sends `G4 P0.5` and holds the next line until its `ok`; the line after
  // it is expanded from the position cncjs has then. On Grbl the dwell's `ok` comes after
  // the motion before it, so `G0 Y[posx]` after `G1 X20` becomes `G0 Y20`.
  const wait = await c.run('wait.nc', 'G21 G90 G0 X0 Y0\nG1 X20 F1500\n%wait\nG0 Y[posx]\n', 60000);
  check(wait.end[0] === 20000 && wait.end[1] === 20000, `%wait: ended at ${fmt(wait.end)}, not 20.000,20.000 ('G0 Y[posx]' after the dwell saw a stale position)`);
  console.log(`  %wait: 'G0 Y[posx]' after 'G1 X20' and the dwell became 'G0 Y20': ended ${fmt(wait.end)}`);
}

async function pauseResume(c) {
  // Pause and resume (the UI's buttons: `!` and `~`).
  const star = readProgram('bench/star.nc');
  await c.run('origin.nc', 'G21 G90 G0 X0 Y0\n', 30000);
  const from = c.reads.length;
  await c.start('star.nc', star);
  await c.until(() => c.status().activeState === 'Run', 10000, 'Run');
  await sleep(700);
  c.command('gcode:pause');
  await c.until(() => c.status().activeState === 'Hold' && c.status().subState === 0, 10000, 'Hold:0');
  const held = c.mpos();
  await sleep(600);
  check(c.status().activeState === 'Hold' && c.mpos().join() === held.join(), `pause: moved while held (${fmt(held)} -> ${c.describe()})`);
  c.command('gcode:resume');
  await c.finish(120000);
  const bad = c.problems(from);
  check(bad.length === 0, `pause/resume: ${bad.join(' | ')}`);
  check(c.mpos()[0] === 0 && c.mpos()[1] === 0, `pause/resume: ended at ${fmt(c.mpos())}, not 0,0`);
  console.log(`  pause at ${fmt(held)}, no motion while held, resume: star.nc ended ${fmt(c.mpos())}, no error`);
}

async function stop(c) {
  const star = readProgram('bench/star.nc');
  // Stop (the UI's stop button: `!`, then after 500 ms a soft reset once the machine
  // holds). A reset at rest in a hold keeps the position, as on Grbl: no alarm.
  const from = c.reads.length;
  await c.start('star.nc', star);
  await c.until(() => c.status().activeState === 'Run', 10000, 'Run');
  await sleep(700);
  c.command('gcode:stop', { force: true });
  await c.until(() => c.workflow === 'idle', 5000, 'the workflow to stop');
  await c.until(() => c.status().activeState === 'Hold', 5000, 'Hold');
  await c.until(() => c.status().activeState === 'Idle', 5000, 'Idle after the reset');
  const stopped = c.mpos();
  await sleep(600);
  check(c.status().activeState === 'Idle' && c.mpos().join() === stopped.join(), `stop: moved after the reset: ${c.describe()}`);
  const bad = c.problems(from);
  check(bad.length === 0, `stop: ${bad.join(' | ')}`);
  const back = await c.run('home.nc', 'G21 G90 G0 X0 Y0\n', 30000);
  check(back.end[0] === 0 && back.end[1] === 0, `after stop: G0 X0 Y0 ended at ${fmt(back.end)}`);
  console.log(`  stop at ${fmt(stopped)}: held, reset without alarm, then G0 X0 Y0 ended ${fmt(back.end)}`);
}

const GROUPS = {
  streams: [
    ['bench/star.nc, streamed by cncjs', starStream],
    ['many short segments', segmentStream],
  ],
  timing: [
    ['%wait macro (G4 as a sync point)', waitMacro],
    ['pause and resume', pauseResume],
    ['stop', stop],
  ],
};

// Runs every check of the group, each on its own (a failed one does not hide the others),
// and ends with a 'N passed, M failed' line.
async function main() {
  const checks = GROUPS[GROUP];
  if (!checks) {
    console.log(`usage: node cncjs.js PORT REPO_ROOT ${Object.keys(GROUPS).join('|')}`);
    return 2;
  }
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'inkstep-cncjs-'));
  let cncjs = null;
  let c = null;
  let passed = 0;
  let failed = 0;
  try {
    cncjs = await startCncjs(dir);
    c = new Client(cncjs.url);
    await c.open();
    console.log(`cncjs ${require('cncjs/package.json').version} opened ${PORT}`);
    for (const [name, f] of checks) {
      console.log(name);
      try {
        await f(c);
        passed++;
      } catch (e) {
        if (!(e instanceof Fail)) throw e;
        failed++;
        console.log(`  FAIL: ${e.message}`);
        // Leave the board idle and cncjs's workflow stopped for the next check.
        c.command('gcode:stop', { force: true });
        await sleep(1000);
        c.command('reset');
        await sleep(500);
        c.command('unlock');
        await sleep(500);
      }
    }
    await c.emit('close', PORT);
  } catch (e) {
    failed++;
    console.log(`FAIL: ${e instanceof Fail ? e.message : e.stack}`);
    console.log(fs.readFileSync(path.join(dir, 'cncjs.log'), 'utf8').split('\n').slice(-20).join('\n'));
  } finally {
    if (c) c.socket.close();
    if (cncjs) cncjs.child.kill();
    fs.rmSync(dir, { recursive: true, force: true });
  }
  console.log(`cncjs ${GROUP}: ${passed} passed, ${failed} failed`);
  return failed ? 1 : 0;
}

main().then((code) => process.exit(code));
