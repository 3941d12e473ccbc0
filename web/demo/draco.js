// Draco's WASM decoder from the draco3d npm package (served as /draco/), for the benches.
function loadScript(src) {
  return new Promise((resolve, reject) => {
    const s = document.createElement('script');
    s.src = src; s.onload = resolve; s.onerror = () => reject(new Error('cannot load ' + src));
    document.head.appendChild(s);
  });
}

export async function loadDraco() {
  await loadScript('/draco/draco_decoder_nodejs.js');
  const wasmBinary = await (await fetch('/draco/draco_decoder.wasm')).arrayBuffer();
  return await new Promise((resolve) => { window.DracoDecoderModule({ wasmBinary }).then((m) => resolve(m)); });
}
