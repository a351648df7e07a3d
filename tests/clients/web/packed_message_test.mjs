// The page's unpacking of Packed messages (clients/web/src/packed_message.js) on the golden ones
// (written from the spec by make_v2_fixtures.py): each holds its golden plain message byte for
// byte; forged fields and a corrupt stream are one-line ProtocolErrors.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { readFixture, webSource } from './support/fixtures.mjs';

const { unpackMessage } = await import(webSource('packed_message.js'));
const { ProtocolError } = await import(webSource('protocol.js'));

test('the golden Packed messages hold the golden plain ones', async () => {
  for (const [packed, plain] of [['packed_mesh_info_v2.bin', 'mesh_info_v2.bin'], ['packed_model.bin', 'model.bin']]) {
    const unpacked = await unpackMessage(readFixture(packed));
    assert.deepEqual(new Uint8Array(unpacked), new Uint8Array(readFixture(plain)), packed);
  }
});

function forged(offset, setter) {
  const copy = readFixture('packed_mesh_info_v2.bin').slice(0);
  setter(new DataView(copy), 12 + offset);
  return copy;
}

test('forged fields and corrupt streams are refused with the reason', async () => {
  const good = readFixture('packed_mesh_info_v2.bin');
  const size = new DataView(good).getUint32(12 + 4, true);
  const longer = new Uint8Array(good.byteLength + 1);
  longer.set(new Uint8Array(good));
  const corrupt = forged(8 + 20 + 3, (v, o) => v.setUint8(o, v.getUint8(o) ^ 0xff));
  const cases = [
    [forged(0, (v, o) => v.setUint16(o, 3, true)), /type 3 \(only MeshInfo and Model are packed\)/],
    [forged(2, (v, o) => v.setUint16(o, 1, true)), /reserved field is 1/],
    [forged(4, (v, o) => v.setUint32(o, 100 << 20, true)), /over the limit/],
    [forged(4, (v, o) => v.setUint32(o, 5, true)), /shorter than its counts/],
    [forged(4, (v, o) => v.setUint32(o, 60_000_000, true)), /deflated bytes cannot make/],
    [forged(8 + 4, (v, o) => v.setUint32(o, 1_000_000, true)), /face count needs 12000000 bytes/],
    [forged(4, (v, o) => v.setUint32(o, size + 1, true)), /the unpacked size says/],
    [forged(4, (v, o) => v.setUint32(o, size - 1, true)), /makes more than the unpacked size/],
    [longer.buffer, /Packed/],
    [corrupt, /Packed/],
    [good.slice(0, 12 + 6), /truncated/],
  ];
  for (const [buffer, pattern] of cases) {
    await assert.rejects(unpackMessage(buffer), (error) => {
      assert.ok(error instanceof ProtocolError, `${pattern}: ${error.name}: ${error.message}`);
      assert.match(error.message, pattern);
      assert.doesNotMatch(error.message, /\n/);
      return true;
    });
  }
});
