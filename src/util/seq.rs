//! Helpers over lists.

/// The first item of `items` that repeats an earlier one (`None` when all differ): what
/// a check of names, seeds or files "listed twice" reports.
pub fn first_repeat<T: PartialEq>(items: &[T]) -> Option<&T> {
    (1..items.len()).find_map(|i| items[..i].contains(&items[i]).then(|| &items[i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_item_seen_before_is_reported() {
        assert_eq!(first_repeat::<u32>(&[]), None);
        assert_eq!(first_repeat(&[1, 2, 3]), None);
        // 2 repeats at index 3, 1 only at index 4: 2 comes first.
        assert_eq!(first_repeat(&[1, 2, 3, 2, 1]), Some(&2));
        assert_eq!(first_repeat(&["a", "a"]), Some(&"a"));
    }
}
