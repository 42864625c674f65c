//! The size expressions of ISF passes (`"WIDTH": "floor($WIDTH/3.0)"`): arithmetic over
//! `$WIDTH`, `$HEIGHT` and `$<input>`, with the functions ISF files use. Hand-written rather than
//! a crate: the grammar is a dozen lines, and a pass size needs a bounded result and a message that
//! says which part did not parse, not a general scripting language.

/// The functions an expression may call, with their argument counts.
const FUNCTIONS: &[(&str, usize)] = &[
    ("floor", 1),
    ("ceil", 1),
    ("round", 1),
    ("abs", 1),
    ("sqrt", 1),
    ("min", 2),
    ("max", 2),
    ("pow", 2),
    ("clamp", 3),
];

/// Evaluates `text` with `$name` looked up by `var`; `Err` says what did not parse.
pub fn evaluate(text: &str, var: &dyn Fn(&str) -> Option<f64>) -> Result<f64, String> {
    let mut p = Parser { s: text.as_bytes(), at: 0, var, depth: 0 };
    let v = p.sum()?;
    p.skip_space();
    if p.at != p.s.len() {
        return Err(format!("'{text}': unexpected '{}'", &text[p.at..]));
    }
    Ok(v)
}

struct Parser<'a> {
    s: &'a [u8],
    at: usize,
    var: &'a dyn Fn(&str) -> Option<f64>,
    depth: u32,
}

impl Parser<'_> {
    fn skip_space(&mut self) {
        while self.s.get(self.at).is_some_and(u8::is_ascii_whitespace) {
            self.at += 1;
        }
    }

    fn eat(&mut self, c: u8) -> bool {
        self.skip_space();
        let hit = self.s.get(self.at) == Some(&c);
        self.at += usize::from(hit);
        hit
    }

    fn sum(&mut self) -> Result<f64, String> {
        let mut v = self.product()?;
        loop {
            if self.eat(b'+') {
                v += self.product()?;
            } else if self.eat(b'-') {
                v -= self.product()?;
            } else {
                return Ok(v);
            }
        }
    }

    fn product(&mut self) -> Result<f64, String> {
        let mut v = self.unary()?;
        loop {
            if self.eat(b'*') {
                v *= self.unary()?;
            } else if self.eat(b'/') {
                v /= self.unary()?;
            } else if self.eat(b'%') {
                v %= self.unary()?;
            } else {
                return Ok(v);
            }
        }
    }

    fn unary(&mut self) -> Result<f64, String> {
        // Bounded nesting: a hostile file cannot overflow the stack.
        self.depth += 1;
        if self.depth > 64 {
            return Err("the expression nests too deeply".into());
        }
        let v = if self.eat(b'-') {
            -self.unary()?
        } else if self.eat(b'+') {
            self.unary()?
        } else {
            self.primary()?
        };
        self.depth -= 1;
        Ok(v)
    }

    fn word(&mut self) -> &str {
        let start = self.at;
        while self.s.get(self.at).is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_') {
            self.at += 1;
        }
        std::str::from_utf8(&self.s[start..self.at]).unwrap_or_default()
    }

    fn primary(&mut self) -> Result<f64, String> {
        self.skip_space();
        let start = self.at;
        if self.eat(b'(') {
            let v = self.sum()?;
            return if self.eat(b')') { Ok(v) } else { Err("a '(' is never closed".into()) };
        }
        if self.eat(b'$') {
            let name = self.word().to_string();
            return (self.var)(&name).ok_or_else(|| format!("unknown variable ${name}"));
        }
        let c = self.s.get(self.at).copied().unwrap_or(b' ');
        if c.is_ascii_digit() || c == b'.' {
            while self.s.get(self.at).is_some_and(|c| c.is_ascii_digit() || *c == b'.' || *c == b'e') {
                self.at += 1;
            }
            let text = std::str::from_utf8(&self.s[start..self.at]).unwrap_or_default();
            return text.parse().map_err(|_| format!("'{text}' is not a number"));
        }
        let name = self.word().to_string();
        let Some(&(_, arity)) = FUNCTIONS.iter().find(|(f, _)| *f == name) else {
            return Err(if name.is_empty() {
                "expected a number, $WIDTH, $HEIGHT, $input or a function".to_string()
            } else {
                let known: Vec<&str> = FUNCTIONS.iter().map(|(f, _)| *f).collect();
                format!("unknown function '{name}' (known: {})", known.join(", "))
            });
        };
        if !self.eat(b'(') {
            return Err(format!("'{name}' must be called: {name}(…)"));
        }
        let mut args = vec![self.sum()?];
        while self.eat(b',') {
            args.push(self.sum()?);
        }
        if !self.eat(b')') || args.len() != arity {
            return Err(format!("{name} takes {arity} argument(s) in parentheses"));
        }
        Ok(match name.as_str() {
            "floor" => args[0].floor(),
            "ceil" => args[0].ceil(),
            "round" => args[0].round(),
            "abs" => args[0].abs(),
            "sqrt" => args[0].sqrt(),
            "min" => args[0].min(args[1]),
            "max" => args[0].max(args[1]),
            "pow" => args[0].powf(args[1]),
            _ => args[0].max(args[1]).min(args[2]),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(text: &str) -> Result<f64, String> {
        evaluate(text, &|n| match n {
            "WIDTH" => Some(1920.0),
            "HEIGHT" => Some(1080.0),
            "scale" => Some(0.5),
            _ => None,
        })
    }

    #[test]
    fn size_expressions_evaluate() {
        assert_eq!(eval("floor($WIDTH/3.0)"), Ok(640.0));
        assert_eq!(eval("$HEIGHT * $scale + 1"), Ok(541.0));
        assert_eq!(eval("max(1, -$WIDTH)"), Ok(1.0));
        assert_eq!(eval("clamp($WIDTH, 1.0, 16)"), Ok(16.0));
        assert_eq!(eval("2 * (3 + 4) - 8 % 3"), Ok(12.0));
        assert_eq!(eval("1"), Ok(1.0));
    }

    #[test]
    fn bad_expressions_say_why() {
        assert!(eval("$DEPTH").unwrap_err().contains("$DEPTH"));
        assert!(eval("floor($WIDTH").unwrap_err().contains("floor"));
        assert!(eval("sin(1)").unwrap_err().contains("unknown function 'sin'"));
        assert!(eval("1 2").is_err());
        assert!(eval(&"(".repeat(200)).is_err());
        assert!(eval("").is_err());
    }
}
