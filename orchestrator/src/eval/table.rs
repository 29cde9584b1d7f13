//! The plain CSV of `runs.csv` and `summary.csv`. Fields never hold commas, quotes or
//! line breaks (the writers make sure), so no quoting is needed; numbers are written
//! with Rust's shortest round-trip formatting, so they read back bit for bit.

use anyhow::{Context, bail};

/// A header and rows of text fields.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    /// Column names.
    pub header: Vec<String>,
    /// Rows, each as long as the header.
    pub rows: Vec<Vec<String>>,
}

/// A field safe for the plain CSV (commas and line breaks become `;` and spaces).
pub fn field(s: &str) -> String {
    s.replace(',', ";").replace(['\n', '\r', '"'], " ")
}

impl Table {
    /// The CSV text, one line per row, `\n` line ends.
    pub fn to_csv(&self) -> String {
        let mut s = self.header.join(",");
        s.push('\n');
        for r in &self.rows {
            s.push_str(&r.join(","));
            s.push('\n');
        }
        s
    }

    /// Parse CSV text written by [`Table::to_csv`]; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> anyhow::Result<Self> {
        let mut lines = text.lines();
        let header: Vec<String> = lines
            .next()
            .ok_or_else(|| anyhow::anyhow!("{origin}: empty"))?
            .split(',')
            .map(str::to_string)
            .collect();
        let mut rows = Vec::new();
        for (i, l) in lines.enumerate() {
            let r: Vec<String> = l.split(',').map(str::to_string).collect();
            if r.len() != header.len() {
                bail!(
                    "{origin}: line {} has {} fields, the header {}",
                    i + 2,
                    r.len(),
                    header.len()
                );
            }
            rows.push(r);
        }
        Ok(Self { header, rows })
    }

    /// Index of column `name`.
    pub fn col(&self, name: &str) -> anyhow::Result<usize> {
        self.header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| anyhow::anyhow!("no column `{name}` in {:?}", self.header))
    }

    /// Field `name` of row `r`.
    pub fn str(&self, r: usize, name: &str) -> anyhow::Result<&str> {
        let c = self.col(name)?;
        Ok(&self.rows[r][c])
    }

    /// Field `name` of row `r` as a number.
    pub fn f64(&self, r: usize, name: &str) -> anyhow::Result<f64> {
        let s = self.str(r, name)?;
        s.parse()
            .with_context(|| format!("row {r}, column `{name}`: `{s}` is not a number"))
    }

    /// Field `name` of row `r` as a count.
    pub fn usize(&self, r: usize, name: &str) -> anyhow::Result<usize> {
        let s = self.str(r, name)?;
        s.parse()
            .with_context(|| format!("row {r}, column `{name}`: `{s}` is not a count"))
    }

    /// Field `name` of row `r` as a flag (`1`/`0`).
    pub fn flag(&self, r: usize, name: &str) -> anyhow::Result<bool> {
        Ok(self.usize(r, name)? != 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_numbers_exactly() {
        let v = [0.1 + 0.2, 1.0 / 3.0, f64::NAN, 1e-300];
        let t = Table {
            header: vec!["a".into(), "b".into()],
            rows: v
                .iter()
                .map(|x| vec![x.to_string(), field("x,y")])
                .collect(),
        };
        let back = Table::parse(&t.to_csv(), "t").unwrap();
        for (r, x) in v.iter().enumerate() {
            assert_eq!(back.f64(r, "a").unwrap().to_bits(), x.to_bits());
            assert_eq!(back.str(r, "b").unwrap(), "x;y");
        }
        assert!(Table::parse("a,b\n1\n", "t").is_err());
    }
}
