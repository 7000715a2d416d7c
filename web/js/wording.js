// The core's messages are written for the command line (likeness fit
// prints them too); the page says the same in its own words: no flags to
// pass, no file-format jargon. Plain functions of text (tested in Node by
// tests/browser/wording_node.mjs).

// "1 photo", "8 photos".
export const photoCount = (n) => n + (n === 1 ? ' photo' : ' photos');

// A fit note or error from the core, for the page.
export function forPage(text) {
  return String(text)
    // The page turned the scan itself; there is no flag to pass in the page.
    .replace(/: turned it that way; pass --facing [-\d. ]+ --up [-\d. ]+ to say so/,
             ': the head was turned that way before fitting')
    .replace(/; try --facing [-\d. ]+ --up [-\d. ]+/,
             '; turn the scan so the face looks along its +z axis with +y up, and load it again')
    .replace(/: pass --up and --facing, e\.g\. --up \+z\)/,
             ': turn the scan so the face looks along its +z axis with +y up, and load it again)')
    .replace(/\(use --whole-head \/ --face-only to force\)/, '')
    .replace(/bbox diagonal/g, 'the scan\'s size (the diagonal of the box around it)');
}
