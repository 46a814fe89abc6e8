// llfsm's page, built into the Python package (llfsm/web/static/app/), where the server serves it
// with no network: fixed file names (the server lists them), no hashes, no CDN, no web fonts.
import { defineConfig } from "vitest/config";
import { fileURLToPath } from "node:url";

const out = fileURLToPath(new URL("../llfsm/web/static/app", import.meta.url));

export default defineConfig({
  oxc: { jsx: { runtime: "automatic", importSource: "preact" } },
  build: {
    outDir: out,
    emptyOutDir: true,
    target: "es2022",
    sourcemap: false,
    cssCodeSplit: false,
    modulePreload: false,
    reportCompressedSize: false,
    chunkSizeWarningLimit: 1024, // one file, served from loopback
    rolldownOptions: {
      input: fileURLToPath(new URL("src/main.tsx", import.meta.url)),
      output: {
        entryFileNames: "app.js",
        chunkFileNames: "app-[name].js",
        assetFileNames: "app[extname]",
      },
    },
  },
  test: {
    environment: "happy-dom",
    globals: true,
    include: ["src/**/*.test.ts", "src/**/*.test.tsx"],
  },
});
