const b = require(process.argv[2]);
const nv = b.positions.length, nt = b.cells.length;
const buf = Buffer.alloc(8 + nv * 12 + nt * 6);
buf.writeUInt32LE(nv, 0); buf.writeUInt32LE(nt, 4);
let o = 8;
for (const p of b.positions) for (const x of p) { buf.writeFloatLE(x, o); o += 4; }
for (const c of b.cells) for (const i of c) { buf.writeUInt16LE(i, o); o += 2; }
require('fs').writeFileSync(process.argv[3], buf);
console.log(nv, nt, buf.length);
