#!/usr/bin/env perl
# Seeds for the fuzzer from the tests: every C++ string literal (raw or ordinary, adjacent
# ordinary ones joined) that looks like a script, one file each in DIR.
#   perl tests/fuzz/extract_snippets.pl DIR tests/lang/*.cpp tests/compiler/*.cpp ...
use strict;
use warnings;

my $dir = shift or die "usage: $0 DIR FILE...\n";
my %seen;
my $n = 0;

sub unescape {
    my ($s) = @_;
    $s =~ s/\\(x[0-9a-fA-F]{1,2}|[0-7]{1,3}|.)/
        my $e = $1;
        $e =~ m{^x} ? chr(hex(substr($e, 1))) :
        $e =~ m{^[0-7]} ? chr(oct($e)) :
        $e eq 'n' ? "\n" : $e eq 't' ? "\t" : $e eq 'r' ? "\r" : $e/ge;
    return $s;
}

sub emit {
    my ($text) = @_;
    return if length($text) < 4 || $text !~ /[;}]/ || $seen{$text}++;
    my $path = sprintf("%s/snippet-%04d.sdf", $dir, $n++);
    open(my $out, '>:raw', $path) or die "$path: $!\n";
    print $out $text;
    close($out);
}

for my $file (@ARGV) {
    open(my $fh, '<:raw', $file) or die "$file: $!\n";
    my $src = do { local $/; <$fh> };
    close($fh);
    while ($src =~ /R"([^(\s"]{0,16})\((.*?)\)\1"/sg) { emit($2); }
    $src =~ s/R"([^(\s"]{0,16})\(.*?\)\1"//sg;
    $src =~ s/'(?:[^'\\\n]|\\.)'//g;  # character literals ('"')
    while ($src =~ /((?:"(?:[^"\\\n]|\\.)*"\s*)+)/g) {
        my $chunk = $1;
        my $text = '';
        while ($chunk =~ /"((?:[^"\\\n]|\\.)*)"/g) { $text .= unescape($1); }
        emit($text);
    }
}
print "$n snippets\n";
