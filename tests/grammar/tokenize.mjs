// Tokenises .sdf files with grammar/sdf.tmLanguage.json through vscode-textmate and
// vscode-oniguruma (what VS Code runs) and checks what each token is scoped as against what
// its text is: keywords, numbers, strings, comments, built-in names, user definitions. A
// sample with every kind of token is checked scope by scope first.
//   node tokenize.mjs GRAMMAR.json FILE.sdf...      (exit 1 on the first wrong scope)
import fs from 'node:fs';
import path from 'node:path';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const vsctm = require('vscode-textmate');
const oniguruma = require('vscode-oniguruma');

const [grammarPath, ...files] = process.argv.slice(2);
const wasm = fs.readFileSync(path.join(path.dirname(require.resolve('vscode-oniguruma')), 'onig.wasm'));
await oniguruma.loadWASM(wasm.buffer.slice(wasm.byteOffset, wasm.byteOffset + wasm.byteLength));
const registry = new vsctm.Registry({
  onigLib: Promise.resolve({ createOnigScanner: (p) => new oniguruma.OnigScanner(p), createOnigString: (s) => new oniguruma.OnigString(s) }),
  loadGrammar: async () => vsctm.parseRawGrammar(fs.readFileSync(grammarPath, 'utf8'), grammarPath),
});
const grammar = await registry.loadGrammar('source.sdf');
const json = JSON.parse(fs.readFileSync(grammarPath, 'utf8'));
const builtins = new Set();
for (const rule of json.repository.builtins.patterns) for (const n of /\(([a-z_0-9|]+)\)/.exec(rule.match)[1].split('|')) builtins.add(n);

function tokens(text) {
  const out = [];
  let state = vsctm.INITIAL;
  text.split('\n').forEach((line, i) => {
    const r = grammar.tokenizeLine(line, state);
    for (const t of r.tokens) out.push({ line: i + 1, text: line.slice(t.startIndex, t.endIndex), scopes: t.scopes, next: line.slice(t.endIndex) });
    state = r.ruleStack;
  });
  return out;
}

let failures = 0;
function fail(where, t, why) {
  if (failures++ < 20) console.error(`${where}:${t.line}: '${t.text}' ${why} (scopes: ${t.scopes.join(' ')})`);
}
const has = (t, prefix) => t.scopes.some((s) => s.startsWith(prefix));

// 1. A sample, token by token.
const sample = 'let r = 1.5e-2; // note\ndef f(x) = sphere(x) color("red");\nif (true) translate([0, pi, 2]) box(r);';
const want = [
  ['let', 'storage.type.sdf'], ['r', 'variable.other.declaration.sdf'], ['1.5e-2', 'constant.numeric.sdf'],
  ['//', 'punctuation.definition.comment.sdf'], [' note', 'comment.line.double-slash.sdf'], ['def', 'storage.type.function.sdf'],
  ['f', 'entity.name.function.sdf'], ['sphere', 'support.function.shape.primitive.sdf'], ['color', 'support.function.material.sdf'],
  ['red', 'string.quoted.double.sdf'], ['if', 'keyword.control.sdf'], ['true', 'constant.language.boolean.sdf'],
  ['translate', 'support.function.shape.modifier.sdf'], ['pi', 'constant.language.sdf'], ['box', 'support.function.shape.primitive.sdf'],
];
const st = tokens(sample);
for (const [text, scope] of want) {
  const t = st.find((k) => k.text === text || k.text.trim() === text.trim());
  if (!t) { failures++; console.error(`sample: no token '${text}'`); continue; }
  if (t.scopes[t.scopes.length - 1] !== scope) fail('sample', t, `is not ${scope}`);
}

// 2. Every file: each token's scope agrees with its text.
const keywords = new Set(['let', 'var', 'def', 'field', 'import', 'if', 'else', 'for']);
const counts = { keyword: 0, number: 0, string: 0, comment: 0, builtin: 0 };
for (const file of files) {
  const text = fs.readFileSync(file, 'utf8');
  for (const t of tokens(text)) {
    const word = t.text.trim();
    if (has(t, 'comment')) { counts.comment++; continue; }
    if (has(t, 'string')) { counts.string++; continue; }
    if (has(t, 'invalid')) fail(file, t, 'is invalid');
    if (keywords.has(word)) {
      counts.keyword++;
      if (!has(t, 'storage.type') && !has(t, 'keyword.control')) fail(file, t, 'is a keyword');
    } else if (/^(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?$/.test(word)) {
      counts.number++;
      if (!has(t, 'constant.numeric')) fail(file, t, 'is a number');
    } else if (builtins.has(word) && /^\s*\(/.test(t.next)) {
      counts.builtin++;
      if (!has(t, 'support.function')) fail(file, t, 'is a built-in call');
    } else if (/^[A-Za-z_]\w*$/.test(word) && has(t, 'support.function')) {
      fail(file, t, 'is no built-in');
    } else if (word.startsWith('//') || word.startsWith('/*')) {
      fail(file, t, 'starts a comment');
    }
  }
  // A comment is never code: the text after // on a line is all comment.
  text.split('\n').forEach((line, i) => {
    const at = line.indexOf('//');
    if (at === 0) {
      const t = tokens(line)[0];
      if (t && !has(t, 'comment')) fail(file, { ...t, line: i + 1 }, 'is a comment line');
    }
  });
}
for (const [k, n] of Object.entries(counts)) if (files.length && n === 0) { failures++; console.error(`no ${k} seen in the files`); }
console.log(`tokenize: ${files.length} files, ${JSON.stringify(counts)}, ${failures} wrong`);
process.exit(failures ? 1 : 0);
