//! The `voxlod` command-line tool.

fn main() {
    println!("voxlod");
}
