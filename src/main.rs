fn main() {
    println!("reshift: the CLI is not built yet");
}
