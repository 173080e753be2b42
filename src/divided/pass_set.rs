//! Which progressive passes a render renders ([`PassSet`]: all of 0..N, a range, or a stride
//! for one of many workers) and which it has rendered ([`PassList`], written into partial films
//! as compact text). Passes are independent given the seed and their index (Knaus & Zwicker's
//! probabilistic form), so disjoint sets rendered anywhere sum to the same image.

/// The largest pass index accepted (2³⁰ − 1): far beyond any render (a pass takes at least
/// milliseconds), and small enough that index arithmetic never overflows and a hostile list
/// cannot ask for unbounded memory.
pub const MAX_INDEX: u32 = (1 << 30) - 1;

/// The most indices a list read from a file may hold (2²⁶, 256 MB as u32).
pub const MAX_LISTED: usize = 1 << 26;

/// The pass indices a render may run, in increasing order: `start, start + step, …` below
/// `end` (`u32::MAX`: no end — a time budget or an error target stops the render).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PassSet {
    /// First index.
    pub start: u32,
    /// Distance between indices (1 for a range).
    pub step: u32,
    /// One past the last index that may be rendered; `u32::MAX` for none.
    pub end: u32,
}

impl PassSet {
    /// Passes 0..`n`.
    #[must_use]
    pub fn first(n: u32) -> Self {
        PassSet { start: 0, step: 1, end: n }
    }

    /// Passes 0, 1, 2, … until the render is stopped.
    #[must_use]
    pub fn unbounded() -> Self {
        PassSet { start: 0, step: 1, end: u32::MAX }
    }

    /// Parses `--passes A..B` (passes A to B − 1) — `None` for a plain count.
    pub fn parse_range(s: &str) -> std::result::Result<Option<Self>, String> {
        let Some((a, b)) = s.split_once("..") else { return Ok(None) };
        let num = |t: &str| {
            t.trim().parse::<u32>().map_err(|_| format!("`{s}`: expected a range A..B of pass indices, such as 32..64"))
        };
        let (a, b) = (num(a)?, num(b)?);
        if b > MAX_INDEX + 1 {
            return Err(format!("`{s}`: pass indices above {MAX_INDEX} are not supported"));
        }
        if a >= b {
            return Err(format!("`{s}`: the range of passes is empty (A..B renders passes A to B−1)"));
        }
        Ok(Some(PassSet { start: a, step: 1, end: b }))
    }

    /// Parses `--pass-set K/N`: passes K, K + N, K + 2N, … (worker K of N), below `end`.
    pub fn parse_stride(s: &str, end: u32) -> std::result::Result<Self, String> {
        let err = || format!("`{s}`: expected K/N, worker K (0-based) of N, such as 3/16");
        let (k, n) = s.split_once('/').ok_or_else(err)?;
        let (k, n): (u32, u32) = (k.trim().parse().map_err(|_| err())?, n.trim().parse().map_err(|_| err())?);
        if n == 0 || k >= n {
            return Err(format!("`{s}`: K must be below N (workers are numbered 0 to N−1)"));
        }
        if n > MAX_INDEX {
            return Err(format!("`{s}`: at most {MAX_INDEX} workers"));
        }
        Ok(PassSet { start: k, step: n, end })
    }

    /// Whether the set has no end.
    #[must_use]
    pub fn is_unbounded(&self) -> bool {
        self.end == u32::MAX
    }

    /// How many indices the set holds (`None` when unbounded).
    #[must_use]
    pub fn count(&self) -> Option<u32> {
        (!self.is_unbounded()).then(|| {
            if self.end <= self.start {
                0
            } else {
                (self.end - self.start).div_ceil(self.step)
            }
        })
    }

    /// The first index of the set after `i` (or its first, for `None`), if any.
    #[must_use]
    pub fn next_after(&self, i: Option<u32>) -> Option<u32> {
        let next = match i {
            None => self.start,
            Some(i) if i < self.start => self.start,
            Some(i) => self.start.checked_add(((i - self.start) / self.step + 1).checked_mul(self.step)?)?,
        };
        (next < self.end && next <= MAX_INDEX).then_some(next)
    }

    /// Whether this is every pass from 0 on, as an undivided render runs them.
    #[must_use]
    pub fn is_whole(&self) -> bool {
        self.start == 0 && self.step == 1
    }

    /// `0..64`, `32..64`, `3/16 below 64`, `3/16`.
    #[must_use]
    pub fn describe(&self) -> String {
        match (self.step, self.is_unbounded()) {
            (1, false) => format!("passes {}..{}", self.start, self.end),
            (1, true) => format!("passes {}..", self.start),
            (n, false) => format!("pass set {}/{n} below {}", self.start, self.end),
            (n, true) => format!("pass set {}/{n}", self.start),
        }
    }
}

/// Pass indices rendered, strictly increasing.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PassList(Vec<u32>);

impl PassList {
    /// The list of `indices` (sorted here); an error names the first index given twice.
    pub fn new(mut indices: Vec<u32>) -> std::result::Result<Self, u32> {
        indices.sort_unstable();
        if let Some(w) = indices.windows(2).find(|w| w[0] == w[1]) {
            return Err(w[0]);
        }
        Ok(PassList(indices))
    }

    /// The indices, increasing.
    #[must_use]
    pub fn indices(&self) -> &[u32] {
        &self.0
    }

    /// How many.
    #[must_use]
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are none.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The largest index.
    #[must_use]
    pub fn last(&self) -> Option<u32> {
        self.0.last().copied()
    }

    /// Appends `i`, which must be larger than every index so far (passes are rendered in
    /// increasing order).
    pub fn push(&mut self, i: u32) {
        assert!(self.last().is_none_or(|l| i > l), "passes are added in increasing order");
        self.0.push(i);
    }

    /// The indices both lists hold.
    #[must_use]
    pub fn overlap(&self, o: &PassList) -> PassList {
        PassList(self.0.iter().copied().filter(|i| o.0.binary_search(i).is_ok()).collect())
    }

    /// The indices below the largest that the list lacks — what is missing from 0..=last — as
    /// their count and compact text (`3..5,9`), without listing them one by one.
    #[must_use]
    pub fn gaps(&self) -> (u64, String) {
        let (mut count, mut runs, mut next) = (0u64, Vec::new(), 0u32);
        for &i in &self.0 {
            if i > next {
                count += u64::from(i - next);
                runs.push(if i - next == 1 { next.to_string() } else { format!("{next}..{i}") });
            }
            next = i + 1;
        }
        (count, runs.join(","))
    }

    /// Compact text: runs of equal steps as `a..b` (step 1, b exclusive) or `a..b/s`, single
    /// indices as `a`, comma-separated — `0..32,40..104/16,7`. [`PassList::parse`] reads it.
    #[must_use]
    pub fn to_text(&self) -> String {
        let v = &self.0;
        let mut parts = Vec::new();
        let mut i = 0;
        while i < v.len() {
            // The longest run from i with a constant step.
            let mut j = i + 1;
            if j < v.len() {
                let step = v[j] - v[i];
                while j + 1 < v.len() && v[j + 1] - v[j] == step {
                    j += 1;
                }
                if j - i >= 2 || step == 1 {
                    let end = v[j] + 1;
                    parts.push(if step == 1 { format!("{}..{end}", v[i]) } else { format!("{}..{end}/{step}", v[i]) });
                    i = j + 1;
                    continue;
                }
            }
            parts.push(v[i].to_string());
            i += 1;
        }
        parts.join(",")
    }

    /// Reads [`PassList::to_text`]'s form; the error says what is wrong with the text.
    pub fn parse(text: &str) -> std::result::Result<Self, String> {
        let bad = |detail: &str| format!("`{text}` is not a list of pass indices: {detail}");
        let mut out = Vec::new();
        for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let num = |t: &str| match t.trim().parse::<u32>() {
                Ok(i) if i <= MAX_INDEX + 1 => Ok(i),
                Ok(_) => Err(bad(&format!("`{t}` is above the largest pass index, {MAX_INDEX}"))),
                Err(_) => Err(bad(&format!("`{t}` is not an index"))),
            };
            let (a, b, step) = match part.split_once("..") {
                None => {
                    let a = num(part)?;
                    (a, a + 1, 1)
                }
                Some((a, rest)) => match rest.split_once('/') {
                    Some((b, st)) => (num(a)?, num(b)?, num(st)?),
                    None => (num(a)?, num(rest)?, 1),
                },
            };
            if step == 0 || a >= b || a > MAX_INDEX {
                return Err(bad(&format!("`{part}` is not a valid run")));
            }
            if out.len() + (b - a).div_ceil(step) as usize > MAX_LISTED {
                return Err(bad(&format!("more than {MAX_LISTED} passes")));
            }
            out.extend((a..b).step_by(step as usize));
        }
        PassList::new(out).map_err(|i| bad(&format!("pass {i} is listed twice")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_read_back_their_text() {
        for v in [vec![], vec![5], vec![0, 1, 2, 3], vec![3, 19, 35, 51], vec![0, 2, 3, 7, 8, 9, 20, 30], vec![1, 9]] {
            let list = PassList::new(v.clone()).unwrap();
            let text = list.to_text();
            assert_eq!(PassList::parse(&text).unwrap().indices(), &v[..], "{text}");
        }
        assert_eq!(PassList::new(vec![3, 19, 35, 51]).unwrap().to_text(), "3..52/16");
        assert_eq!(PassList::new(vec![0, 1, 2, 9]).unwrap().to_text(), "0..3,9");
        assert!(PassList::parse("1,1").is_err());
        assert!(PassList::parse("4..2").is_err());
        assert!(PassList::parse("x").is_err());
    }

    #[test]
    fn sets_step_through_their_indices() {
        let s = PassSet::parse_stride("3/16", 64).unwrap();
        let mut got = Vec::new();
        let mut i = None;
        while let Some(n) = s.next_after(i) {
            got.push(n);
            i = Some(n);
        }
        assert_eq!(got, [3, 19, 35, 51]);
        assert_eq!(s.count(), Some(4));
        assert_eq!(PassSet::parse_range("32..64").unwrap(), Some(PassSet { start: 32, step: 1, end: 64 }));
        assert_eq!(PassSet::parse_range("8").unwrap(), None);
        assert!(PassSet::parse_range("9..9").is_err());
        assert!(PassSet::parse_stride("16/16", 5).is_err());
        assert_eq!(PassSet::unbounded().next_after(Some(u32::MAX - 1)), None);
        assert_eq!(PassList::new(vec![0, 3, 4, 7]).unwrap().gaps(), (4, "1..3,5..7".to_string()));
        assert_eq!(PassList::new(vec![2, 3]).unwrap().gaps(), (2, "0..2".to_string()));
        assert!(PassSet::parse_range("0..4000000000").is_err());
        assert_eq!(PassSet::unbounded().next_after(Some(MAX_INDEX)), None);
        // Hostile lists are refused before they are built.
        let many = ["0..60000000"; 3].join(",");
        assert!(PassList::parse(&many).is_err());
        assert!(PassList::parse("4294967295").is_err());
    }
}
