// The core's messages are written for the command line (likeness fit
// prints them too); the page says the same in its own words: no flags to
// pass, no file-format jargon. Plain functions of text (tested in Node by
// tests/browser/wording_node.mjs).
import { snapAxis } from './axes.js';

// "1 photo", "8 photos".
export const photoCount = (n) => n + (n === 1 ? ' photo' : ' photos');

// What to do in the page where the CLI says --up and --facing: the "Scan's
// axes" controls under Fit head (axes.js), named when the core gave axes.
function setAxes(up, facing) {
  const axis = (text) => {
    const v = text ? text.trim().split(/\s+/).map(Number) : [];
    const a = v.length === 3 && snapAxis(v, 1);
    return a ? a.toUpperCase().replace('-', '−') : null;
  };
  const [u, f] = [axis(up), axis(facing)];
  return u && f ? 'set the scan\'s axes under Fit head to up ' + u + ', face looks along ' + f
                : 'set the scan\'s axes under Fit head: which of its axes points to the top of the head, and which one the face looks along';
}

// A fit note or error from the core, for the page.
export function forPage(text) {
  return String(text)
    // The page turned the scan itself; there is no flag to pass in the page.
    .replace(/: turned it that way; pass --facing [-\d. ]+ --up [-\d. ]+ to say so/,
             ': the head was turned that way before fitting')
    .replace(/; try --facing ([-\d. ]+) --up ([-\d. ]+)/, (all, facing, up) => '; ' + setAxes(up, facing))
    .replace(/: pass --up and --facing, e\.g\. --up \+z\)/, ': ' + setAxes() + ')')
    .replace(/\(use --whole-head \/ --face-only to force\)/, '')
    .replace(/bbox diagonal/g, 'the scan\'s size (the diagonal of the box around it)');
}
